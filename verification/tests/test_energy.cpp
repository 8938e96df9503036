// Energy over 1000 pendulum periods: symplectic Euler's error stays bounded, explicit Euler's grows,
// implicit Euler's decays (seeds: energy behaviour of the Euler family).
#include "models/model.hpp"
#include "models/pendulum.hpp"
#include "run/measure.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace stepwise {
namespace {

constexpr double theta0 = 0.5;
constexpr int periods = 1000;

// relative energy error (E - E0)/E0 every T / samples_per_period, dt = T / steps_per_period
std::vector<double> energy_errors(const char* method, int steps_per_period, int samples_per_period = 1) {
  const auto model = make_model("pendulum", {{"theta0", theta0}});
  const double period = pendulum_period(theta0, 9.81, 1.0);
  StepControl control;
  control.dt = period / steps_per_period;
  const Measured m = run_and_measure(*model, method, control, periods * period, period / samples_per_period);
  EXPECT_EQ(m.result.status, Status::ok) << method << ": " << m.result.message;
  const double e0 = *model->energy(model->initial_state());
  std::vector<double> errors;
  for (const auto& y : m.result.trajectory.y) errors.push_back((*model->energy(y) - e0) / e0);
  return errors;
}

double max_abs(const std::vector<double>& v, size_t begin, size_t end) {
  double m = 0;
  for (size_t i = begin; i < end; ++i) m = std::max(m, std::abs(v[i]));
  return m;
}

TEST(Energy, SymplecticEulerStaysBounded) {
  // sampled 20 times a period: the error oscillates within each period, and the numerical period differs
  // from T, so sampling once a period would see a different phase of that oscillation at the start and the end
  const auto e = energy_errors("symplectic-euler", 100, 20);
  const size_t n = e.size(), tenth = n / 10;
  ASSERT_EQ(n, static_cast<size_t>(20 * periods));
  const double first = max_abs(e, 0, tenth), last = max_abs(e, n - tenth, n);
  std::cout << "symplectic Euler: max |dE/E| first 100 periods " << first << ", last 100 " << last << '\n';
  EXPECT_LT(last, tolerance::bounded_energy_growth * first);
  // the modified energy it conserves is H + O(h): the error is of size w h, here 2 pi / 100
  EXPECT_LT(max_abs(e, 0, n), 2 * std::numbers::pi / 100);
}

TEST(Energy, ExplicitEulerGrowsAndImplicitEulerDecays) {
  // per step the linearised amplification is |1 + i w h|^2 = 1 + (w h)^2 (explicit) and 1/(1 + (w h)^2) (implicit)
  const int n = 20000;  // total growth e^{1000 n (wh)^2} ~ 7: the pendulum stays below the separatrix
  const auto ex = energy_errors("euler", n);
  const auto im = energy_errors("implicit-euler", n);
  const double wh = 2 * std::numbers::pi / n;
  const double predicted_after_one = wh * wh * n;  // (1 + (wh)^2)^n - 1 ~ n (wh)^2 for the first period
  std::cout << "after 1 period: explicit " << ex.front() << ", implicit " << im.front() << ", predicted +-"
            << predicted_after_one << "; after " << periods << ": explicit " << ex.back() << ", implicit " << im.back() << '\n';
  EXPECT_NEAR(ex.front(), predicted_after_one, tolerance::linearised_drift_band * predicted_after_one);
  EXPECT_NEAR(im.front(), -predicted_after_one, tolerance::linearised_drift_band * predicted_after_one);
  for (size_t i = 1; i < ex.size(); ++i) {
    ASSERT_GT(ex[i], ex[i - 1]) << "explicit Euler energy grows every period, period " << i;
    ASSERT_LT(im[i], im[i - 1]) << "implicit Euler energy decays every period, period " << i;
  }
  // over all periods the same factors compound: e^{+-1000 n (wh)^2} - 1
  const double compound = 1000 * n * wh * wh;
  EXPECT_NEAR(std::log1p(ex.back()), compound, tolerance::linearised_drift_band * compound);
  EXPECT_NEAR(std::log1p(im.back()), -compound, tolerance::linearised_drift_band * compound);
}

}  // namespace
}  // namespace stepwise
