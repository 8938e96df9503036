// Events in a scene's own equations ([events.NAME], docs/scenes.md): the bouncing ball written as equations
// against its closed form and the built-in model, the accumulation time with a rest rule, Zeno without one, and
// the cases event location gets wrong elsewhere: a graze, a double root, an event at t0, two events in one step,
// a terminal event with output times.
#include "models/bouncing_ball.hpp"
#include "models/equations.hpp"
#include "run/scene.hpp"
#include "solvers/method_table.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace stepwise {
namespace {

std::unique_ptr<Model> model_of(std::string_view toml, const Params& values = {}) {
  const Scene scene = load_scene_text(toml, "test.toml");
  return make_equations(*scene.equations, values, false);
}

std::unique_ptr<Model> ball_equations(const Params& values = {}) {
  return make_equations(*load_scene(std::string(STEPWISE_SOURCE_DIR) + "/scenes/bouncing-ball-equations.toml").equations, values, false);
}

RunResult run(const Model& model, std::string_view method, const StepControl& control, std::vector<double> t_out) {
  return make_integrator(method, control)->integrate(model, 0, model.initial_state(), t_out);
}

const Params ball{{"height", 1.0}, {"restitution", 0.8}, {"g", 9.81}, {"rest_speed", 0.01}};

TEST(EquationEvents, TheBallsImpactTimesAreTheClosedFormsToTheMethodsTolerance) {
  const auto exact = bouncing_ball_impacts(ball, 1000);
  const auto model = ball_equations();
  const auto builtin = make_model("bouncing-ball", ball);
  const double t_end = exact.back().t + 0.5;
  struct Case {
    const char* method;
    StepControl control;
    double tolerance;
  };
  const double rtol = 1e-10;
  const std::vector<Case> cases{
      {"rk4", StepControl::fixed(1e-3), tolerance::event_time_exact_steps},
      {"gsl-rk8pd", StepControl::fixed(1e-2), tolerance::event_time_exact_steps},
      {"tsitouras54", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"verner98", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"rodas5", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"cvode-adams", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"cvode-bdf", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"arkode-erk-dormand-prince54", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"odeint-dopri5", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"gsl-rkf45", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"gsl-msbdf", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
  };
  for (const Case& c : cases) {
    const RunResult r = run(*model, c.method, c.control, {t_end});
    const RunResult b = run(*builtin, c.method, c.control, {t_end});
    ASSERT_EQ(r.status, Status::ok) << c.method << ": " << r.message;
    ASSERT_EQ(r.events.size(), exact.size()) << c.method;
    double worst = 0, worst_builtin = 0;
    for (size_t n = 0; n < exact.size(); ++n) {
      worst = std::max(worst, std::abs(r.events[n].t - exact[n].t));
      if (n < b.events.size()) worst_builtin = std::max(worst_builtin, std::abs(r.events[n].t - b.events[n].t));
    }
    std::cout << c.method << ": impact times off by " << worst << " (the built-in model's by " << worst_builtin << ")\n";
    EXPECT_LT(worst, c.tolerance) << c.method;
    EXPECT_EQ(r.events.back().kind, "rest") << c.method;
    // the states just before and after each impact are kept: the rebound is -e times the impact speed
    for (const auto& e : r.events) {
      if (e.kind == "crossing") { EXPECT_NEAR(e.after[1], -0.8 * e.before[1], 1e-12) << c.method << " at " << e.t; }
    }
    // at rest: the ball stays on the floor (vy held at 0, the flag set)
    EXPECT_EQ(r.y_stop[1], 0.0) << c.method;
    EXPECT_EQ(r.y_stop[2], 1.0) << c.method;
    EXPECT_LT(std::abs(r.y_stop[0]), 1e-9) << c.method;
  }
}

TEST(EquationEvents, WithARestRuleTheBallRestsAtTheAccumulationTime) {
  // t_inf = t1 (1 + e) / (1 - e); the rest comes at the impact whose rebound e v_r is below rest_speed, short of
  // t_inf by the flights it would still have made, 2 e v_r / (g (1 - e)) < 2 rest_speed / (g (1 - e))
  const double e = 0.8, g = 9.81, rest_speed = 1e-4;
  const auto model = ball_equations({{"rest_speed", rest_speed}});
  const double t1 = std::sqrt(2 / g), t_inf = t1 * (1 + e) / (1 - e);
  const double rtol = 1e-10;
  for (const char* method : {"verner98", "cvode-bdf", "rodas5"}) {
    const RunResult r = run(*model, method, StepControl::adaptive(rtol, 1e-12), {t_inf + 1});
    ASSERT_EQ(r.status, Status::ok) << method << ": " << r.message;
    ASSERT_EQ(r.events.back().kind, "rest") << method;
    const double short_of = t_inf - r.events.back().t;
    std::cout << method << ": rests " << short_of << " s before t_inf after " << r.events.size() << " impacts\n";
    EXPECT_GE(short_of, -tolerance::event_time_per_rtol * rtol) << method;
    EXPECT_LT(short_of, 2 * rest_speed / (g * (1 - e)) + tolerance::event_time_per_rtol * rtol) << method;
  }
}

TEST(EquationEvents, WithoutARestRuleTheBallIsZenoAndTheRunFailsSayingWhen) {
  const auto model = model_of(R"(model = "equations"
variables = ["y", "v"]
[initial]
y = 1.0
v = 0.0
[equations]
y = "v"
v = "-9.81"
[events.floor]
when = "y"
direction = "falling"
action = { v = "-0.8*v" }
)");
  const double t_inf = std::sqrt(2 / 9.81) * 9;
  for (const char* method : {"rk4", "verner98", "tsitouras54", "gsl-rk8pd"}) {
    StepControl control = std::string_view(method) == "rk4" ? StepControl::fixed(1e-3) : StepControl::adaptive(1e-10, 1e-12);
    const RunResult r = run(*model, method, control, {5.0});
    EXPECT_EQ(r.status, Status::failed) << method << " ends " << to_string(r.status) << " with " << r.events.size() << " events";
    EXPECT_NE(r.message.find("Zeno"), std::string::npos) << r.message;
    EXPECT_NEAR(r.t_stop, t_inf, 1e-3) << method;
  }
}

// x' = 1 from 0: g(x) is g(t), each root known
std::string line_with(std::string_view events) {
  return std::string(R"(model = "equations"
variables = ["x"]
[initial]
x = 0.0
[equations]
x = "1"
)") + std::string(events);
}

TEST(EquationEvents, APairOfRootsInsideOneStepIsFoundByTheExtremumBetween) {
  // (x - 1)^2 - d^2: roots at 1 - d and 1 + d, both inside one step of 0.3 from 0.9, where g is positive at
  // both ends
  const auto model = model_of(line_with("[events.graze]\nwhen = \"(x - 1)^2 - 1e-6\"\n"));
  for (const char* method : {"rk4", "gsl-rk8pd"}) {
    const RunResult r = run(*model, method, StepControl::fixed(0.3), {1.5});
    ASSERT_EQ(r.events.size(), 2u) << method;
    EXPECT_NEAR(r.events[0].t, 0.999, tolerance::event_time_located(0.3)) << method;
    EXPECT_NEAR(r.events[1].t, 1.001, tolerance::event_time_located(0.3)) << method;
  }
  const RunResult adaptive = run(*model, "tsitouras54", StepControl::adaptive(1e-8, 1e-10), {1.5});
  ASSERT_EQ(adaptive.events.size(), 2u);
  EXPECT_NEAR(adaptive.events[0].t, 0.999, 1e-9);
  EXPECT_NEAR(adaptive.events[1].t, 1.001, 1e-9);
}

TEST(EquationEvents, ADoubleRootIsFoundOnce) {
  // (x - 1)^2 touches zero at t = 1 without crossing it: it reaches the level once
  const auto model = model_of(line_with("[events.touch]\nwhen = \"(x - 1)^2\"\n"));
  const RunResult r = run(*model, "rk4", StepControl::fixed(0.3), {2.0});
  ASSERT_EQ(r.events.size(), 1u);
  EXPECT_NEAR(r.events[0].t, 1.0, 1e-6);  // an extremum is flat: its place is found to sqrt of round-off
}

TEST(EquationEvents, AnEventAtTheStartDoesNotFireUnlessItCrosses) {
  // g = x is 0 at t0 and leaves it: no crossing; g = x - 0.5 crosses at 0.5
  const auto model = model_of(line_with("[events.start]\nwhen = \"x\"\n[events.half]\nwhen = \"x - 0.5\"\ndirection = \"rising\"\n"));
  for (const char* method : {"rk4", "tsitouras54", "cvode-bdf"}) {
    const bool fixed = std::string_view(method) == "rk4";
    const RunResult r = run(*model, method, fixed ? StepControl::fixed(0.1) : StepControl::adaptive(1e-8, 1e-10), {1.0});
    ASSERT_EQ(r.events.size(), 1u) << method;
    EXPECT_EQ(events_of(*model)[r.events[0].event].name, "half") << method;
    EXPECT_NEAR(r.events[0].t, 0.5, 1e-9) << method;
  }
}

TEST(EquationEvents, TwoEventsInOneStepAreAppliedInTimeOrder) {
  // both inside one step of 1: b (at 0.2) before a (at 0.3), whatever their order in the file; each action
  // reads the state of its own time
  const auto model = model_of(R"(model = "equations"
variables = ["x", "seen"]
[initial]
x = 0.0
seen = 0.0
[equations]
x = "1"
seen = "0"
[events.a]
when = "x - 0.3"
action = { seen = "10*seen + 1" }
[events.b]
when = "x - 0.2"
action = { seen = "10*seen + 2" }
)");
  for (const char* method : {"rk4", "euler"}) {
    const RunResult r = run(*model, method, StepControl::fixed(1.0), {1.0});
    ASSERT_EQ(r.events.size(), 2u) << method;
    EXPECT_EQ(events_of(*model)[r.events[0].event].name, "b") << method;
    EXPECT_NEAR(r.events[0].t, 0.2, tolerance::event_time_located(1.0)) << method;
    EXPECT_NEAR(r.events[1].t, 0.3, tolerance::event_time_located(1.0)) << method;
    EXPECT_EQ(r.y_stop[1], 21.0) << method << ": b's action, then a's";
  }
}

TEST(EquationEvents, ATerminalEventEndsTheRunThereWithTheOutputsBeforeIt) {
  const auto model = model_of(line_with("[events.stop]\nwhen = \"x - 0.55\"\nterminal = true\n"));
  for (const char* method : {"rk4", "tsitouras54", "cvode-adams", "gsl-rkf45"}) {
    const bool fixed = std::string_view(method) == "rk4";
    const RunResult r = run(*model, method, fixed ? StepControl::fixed(0.1) : StepControl::adaptive(1e-8, 1e-10),
                            {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0});
    ASSERT_EQ(r.status, Status::ok) << method << ": " << r.message;
    EXPECT_TRUE(r.terminated) << method;
    EXPECT_NEAR(r.t_stop, 0.55, 1e-9) << method;
    ASSERT_EQ(r.trajectory.t.size(), 5u) << method;
    EXPECT_EQ(r.trajectory.t.back(), 0.5) << method;
  }
}

TEST(EquationEvents, WithRecordedStepsTheTrajectoryIsTheStepsTaken) {
  const auto model = ball_equations();
  StepControl control = StepControl::adaptive(1e-8, 1e-10);
  control.record_steps = true;
  for (const char* method : {"tsitouras54", "cvode-bdf", "rk4"}) {
    StepControl c = std::string_view(method) == "rk4" ? StepControl::fixed(0.01) : control;
    c.record_steps = true;
    const RunResult r = run(*model, method, c, {2.0});
    ASSERT_EQ(r.status, Status::ok) << method;
    // every step's end, each event's time among them, and the last output time
    EXPECT_GE(static_cast<long>(r.trajectory.t.size()), r.stats.steps) << method;
    EXPECT_EQ(r.trajectory.t.back(), 2.0) << method;
    for (size_t k = 1; k < r.trajectory.t.size(); ++k) ASSERT_GT(r.trajectory.t[k], r.trajectory.t[k - 1]) << method;
    for (const auto& e : r.events)
      EXPECT_TRUE(std::find(r.trajectory.t.begin(), r.trajectory.t.end(), e.t) != r.trajectory.t.end()) << method << ": the event at " << e.t;
  }
}

}  // namespace
}  // namespace stepwise
