#include "convergence.hpp"

#include "order_fit.hpp"
#include "tolerances.hpp"

#include <cmath>

namespace stepwise {

double coarse_dt(const Method& method, double time_scale) {
  if (method.order.min != method.order.max) return time_scale / 32;
  const int p = method.order.max;
  const double fraction = p <= 1 ? 1.0 / 256 : p <= 3 ? 1.0 / 32 : p <= 4 ? 1.0 / 4 : p <= 5 ? 1.0 / 2 : 1.0;
  return time_scale * fraction;
}

std::vector<double> convergence_steps(const Method& method, int halvings, double coarse) {
  // an eighth-order error falls 256-fold per halving: four halvings span more than the range between the
  // asymptotic ceiling and round-off, so high orders refine by sqrt(2) over the same range of dt
  const int per_halving = method.order.max > 5 ? 2 : 1;
  std::vector<double> dts;
  for (int k = 0; k <= halvings * per_halving; ++k) dts.push_back(coarse / std::pow(2.0, static_cast<double>(k) / per_halving));
  return dts;
}

ConvergenceSweep convergence_sweep(const Model& model, const Method& method, double t_end, int halvings,
                                   double coarse, const Eigen::VectorXd* reference) {
  ConvergenceSweep sweep;
  for (const double dt : convergence_steps(method, halvings, coarse)) {
    StepControl control;
    control.dt = dt;
    sweep.dt.push_back(*control.dt);
    sweep.runs.push_back(run_and_measure(model, method.name, control, t_end, t_end));
    if (reference && sweep.runs.back().result.status == Status::ok) sweep.runs.back().error = max_norm_error(sweep.runs.back().result.y_stop, *reference);
    const auto& error = sweep.runs.back().error;
    if (error && *error > tolerance::roundoff_floor && *error < tolerance::asymptotic_ceiling) {
      sweep.fit_dt.push_back(*control.dt);
      sweep.fit_error.push_back(*error);
    }
  }
  sweep.observed_order = sweep.fit_dt.size() >= 2 ? loglog_slope(sweep.fit_dt, sweep.fit_error) : std::nan("");
  return sweep;
}

}  // namespace stepwise
