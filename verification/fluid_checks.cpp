#include "fluid_checks.hpp"

#include "run/measure.hpp"
#include "solvers/periodic_fft.hpp"
#include "verification/stability.hpp"
#include "verification/tolerances.hpp"

#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <random>

namespace stepwise {

std::unique_ptr<Model> unit_taylor_green(int n, double nu) {
  return make_model("taylor-green", {{"size", n}, {"viscosity", nu}, {"length", 1}, {"mode", 1}, {"amplitude", 1}});
}

double taylor_green_effective_viscosity(const Model& model, double k, const Eigen::VectorXd& y0, const Eigen::VectorXd& y, double t) {
  return -std::log(*model.energy(y) / *model.energy(y0)) / (4 * k * k * t);
}

double taylor_green_viscosity(std::string_view method, int n, double nu, double h, double t_end) {
  const auto model = unit_taylor_green(n, nu);
  StepControl control = StepControl::fixed(h);
  control.observe = [](const Eigen::VectorXd& y) { return y; };
  const Measured m = run_and_measure(*model, method, control, t_end, t_end);
  if (m.result.status != Status::ok) return std::numeric_limits<double>::quiet_NaN();
  return taylor_green_effective_viscosity(*model, 2 * std::numbers::pi, model->initial_state(), m.result.trajectory.y.back(), m.result.trajectory.t.back());
}

std::optional<FluidStepLimits> fluid_step_limits(std::string_view method, int n, double length, double speed_sum, double nu) {
  const double k = 2 * std::numbers::pi / length * PeriodicFft::largest_kept(n);
  const std::complex<double> advective(0, speed_sum * k), viscous(-nu * 2 * k * k, 0);
  const auto limit = [&](std::complex<double> lambda) { return spectrum_stable_dt(method, Eigen::VectorXcd::Constant(1, lambda)); };
  const auto a = limit(advective), v = limit(viscous), c = limit(advective + viscous);
  if (!a || !v || !c) return std::nullopt;
  return FluidStepLimits{*a, *v, *c};
}

double taylor_green_measured_stable_dt(std::string_view method, int n, double nu, long steps, double predicted) {
  const auto model = unit_taylor_green(n, nu);
  Eigen::VectorXd y0 = model->initial_state();
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  for (double& v : y0) v += u(rng);
  const auto bounded = [&](double dt) { return stays_bounded(*model, method, y0, dt, steps); };
  double unstable = 10 * predicted;
  while (bounded(unstable) && unstable < 1e4 * predicted) unstable *= 4;
  return bisect_stability(bounded, predicted / 10, unstable, tolerance::stability_bisection_width);
}

}  // namespace stepwise
