// Events in every integrator, checked on the bouncing ball against its closed form: impact times, apex
// heights eps^(2n) h0, resting contact instead of the Zeno point, and no energy gained at eps = 1.
#include "models/bouncing_ball.hpp"
#include "solvers/method_table.hpp"
#include "run/measure.hpp"
#include "verification/order_fit.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace stepwise {
namespace {

const Params ball_params{{"height", 1.0}, {"restitution", 0.8}, {"g", 9.81}, {"rest_speed", 0.01}};

RunResult run_ball(const Params& params, std::string_view method, StepControl control, std::vector<double> t_out) {
  const auto model = make_model("bouncing-ball", params);
  return make_integrator(method, control)->integrate(*model, 0, model->initial_state(), t_out);
}

TEST(Events, EveryMethodSeesEveryImpactAndTheRest) {
  const auto exact = bouncing_ball_impacts(ball_params, 1000);
  const double t_end = exact.back().t + 0.5;
  for (const auto& method : methods()) {
    if (!method_applies(method, *make_model("bouncing-ball", ball_params))) continue;
    for (const auto location : {EventLocation::linear, EventLocation::restep}) {
      // adaptive where the method can be and is not of low order (rk1imp at rtol 1e-10 takes millions of steps)
      const bool adaptive = method.adaptive() && (!method.fixed_step() || method.order.max > 2);
      StepControl control = adaptive ? StepControl::adaptive(1e-10, 1e-12) : StepControl::fixed(1e-4);
      control.event_location = location;
      const RunResult r = run_ball(ball_params, method.name, control, {t_end});
      ASSERT_EQ(r.status, Status::ok) << method.name << ": " << r.message;
      ASSERT_FALSE(r.events.empty()) << method.name;
      // the first impact, where no earlier event error has accumulated: within the location's error
      const double first_error = std::abs(r.events.front().t - exact.front().t);
      std::cout << method.name << (location == EventLocation::linear ? " linear" : " restep") << ": " << r.events.size()
                << " events (exact " << exact.size() << "), first impact off by " << first_error << ", last "
                << r.events.back().kind << " at " << r.events.back().t << '\n';
      EXPECT_LT(first_error, tolerance::first_impact_any_method) << method.name;
      // at dt = 1e-4 even explicit Euler's energy gain per flight stays below the rest threshold (see below)
      EXPECT_EQ(r.events.back().kind, "rest") << method.name;
      EXPECT_NEAR(r.events.back().t, exact.back().t, tolerance::rest_time_any_method) << method.name;
      EXPECT_EQ(r.trajectory.y.back()[0], 0.0) << method.name << " ends resting on the plane";
    }
  }
}

TEST(Events, CvodeFindsImpactTimesAndApexHeightsToItsTolerance) {
  const auto exact = bouncing_ball_impacts(ball_params, 1000);
  // outputs at the exact apex times: there the height must be eps^(2n) h0
  std::vector<double> apex_times;
  const double g = ball_params.at("g");
  for (size_t n = 0; n + 1 < exact.size(); ++n) apex_times.push_back(exact[n].t + std::sqrt(2 * exact[n].apex / g));
  std::vector<double> t_out = apex_times;
  t_out.push_back(exact.back().t + 0.1);  // after the impact that ends in rest
  for (const char* method : {"cvode-adams", "cvode-bdf"}) {
    const RunResult r = run_ball(ball_params, method, StepControl::adaptive(1e-10, 1e-12), t_out);
    ASSERT_EQ(r.status, Status::ok) << r.message;
    ASSERT_GE(r.events.size(), apex_times.size()) << method;
    double worst_time = 0, worst_height = 0;
    for (size_t n = 0; n < apex_times.size(); ++n) {
      worst_time = std::max(worst_time, std::abs(r.events[n].t - exact[n].t));
      const double expected = std::pow(ball_params.at("restitution"), 2.0 * static_cast<double>(n + 1)) * ball_params.at("height");
      EXPECT_NEAR(exact[n].apex, expected, tolerance::kernel_roundoff);
      worst_height = std::max(worst_height, std::abs(r.trajectory.y[n][0] - expected));
    }
    std::cout << method << ": worst impact time error " << worst_time << " s, worst apex error " << worst_height << " m over "
              << apex_times.size() << " bounces\n";
    // the root is located to CVODE's root tolerance (~100 ulps of t) on a solution accurate to ~rtol
    EXPECT_LT(worst_time, tolerance::event_time_adaptive);
    EXPECT_LT(worst_height, tolerance::event_time_adaptive);
    EXPECT_EQ(r.events.size(), exact.size()) << method;
    EXPECT_EQ(r.events.back().kind, "rest") << method;
    EXPECT_EQ(r.trajectory.y.back(), Eigen::Vector2d(0, 0)) << method << " rests on the plane";
  }
}

TEST(Events, TheSegmentMethodsErrorShrinksAtItsOrderAndReSteppingRemovesIt) {
  // rk4 is exact on the parabola, so the first impact's error is the segment method's own: the chord of
  // y(t) over the step meets the plane early by ~g h^2 / (8 v), order 2. Explicit Euler's own O(h) error
  // dominates its event time: order 1. Re-stepping to the root leaves round-off.
  const double t1 = bouncing_ball_impacts(ball_params, 1).front().t;
  for (const auto& [method, order] : {std::pair{"rk4", 2.0}, std::pair{"euler", 1.0}}) {
    std::vector<double> dts, errors;
    for (int k = 0; k <= 5; ++k) {
      const double dt = 0.01 / std::pow(2.0, k);
      const RunResult r = run_ball(ball_params, method, StepControl::fixed(dt), {0.6});
      ASSERT_FALSE(r.events.empty());
      dts.push_back(dt);
      errors.push_back(std::abs(r.events.front().t - t1));
    }
    const double slope = loglog_slope(dts, errors);
    std::cout << method << " segment method: first impact error " << errors.front() << " -> " << errors.back()
              << ", order " << slope << '\n';
    EXPECT_NEAR(slope, order, tolerance::order_band) << method;
  }
  StepControl control = StepControl::fixed(0.01);
  control.event_location = EventLocation::restep;
  const RunResult r = run_ball(ball_params, "rk4", control, {0.6});
  EXPECT_NEAR(r.events.front().t, t1, tolerance::event_time_restep);
}

TEST(Events, NoEnergyIsGainedOverTenThousandElasticBounces) {
  // eps = 1; a rest speed of 1 m/s only bounds the adaptive step (no rebound is that slow at h0 = 1 m)
  const Params elastic{{"height", 1.0}, {"restitution", 1.0}, {"g", 9.81}, {"rest_speed", 1.0}};
  const auto model = make_model("bouncing-ball", elastic);
  const double e0 = *model->energy(model->initial_state());
  const double t_end = bouncing_ball_impacts(elastic, 10'000).back().t + 0.1;
  for (const auto location : {EventLocation::linear, EventLocation::restep}) {
    StepControl control = StepControl::fixed(1e-2);
    control.event_location = location;
    const RunResult r = run_ball(elastic, "rk4", control, {t_end});
    ASSERT_EQ(r.status, Status::ok);
    ASSERT_GE(r.events.size(), 10'000u);
    const double drift = (*model->energy(r.trajectory.y.back()) - e0) / e0;
    std::cout << (location == EventLocation::linear ? "linear" : "restep") << ": relative energy change after "
              << r.events.size() << " bounces " << drift << '\n';
    // the chord of the concave y(t) meets the plane before the parabola does, where the ball is slower:
    // the segment method can only lose energy; re-stepping keeps it to round-off
    EXPECT_LE(drift, tolerance::roundoff_per_step * std::numeric_limits<double>::epsilon() * static_cast<double>(r.events.size()));
    if (location == EventLocation::restep) {
      EXPECT_GT(drift, -tolerance::event_energy_roundoff);
    }
  }
}

TEST(Events, ExplicitEulerNeverLetsTheBallRest) {
  // over a short flight explicit Euler's position lags its velocity, so the ball lands faster than it left:
  // an impact speed v gains ~g h per flight, and the rebound eps (v + g h) settles at v* = eps g h / (1 - eps),
  // above the rest speed whenever h > rest_speed (1 - eps) / (eps g)
  const double h = 1e-3;
  const RunResult r = run_ball(ball_params, "euler", StepControl::fixed(h), {10.0});
  ASSERT_EQ(r.status, Status::ok);
  EXPECT_EQ(r.events.back().kind, "impact");
  const double eps = ball_params.at("restitution"), g = ball_params.at("g");
  const double v_star = eps * g * h / (1 - eps);
  EXPECT_GT(v_star, ball_params.at("rest_speed"));
  std::cout << "explicit Euler: " << r.events.size() << " impacts in 10 s, predicted limit rebound " << v_star << " m/s\n";
}

}  // namespace
}  // namespace stepwise
