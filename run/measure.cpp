#include "measure.hpp"

#include <fmt/format.h>

#include <cmath>

namespace stepwise {

std::vector<double> output_times(double t_end, double output_dt) {
  std::vector<double> t;
  const auto n = static_cast<long>(std::floor(t_end / output_dt * (1 + 1e-12)));
  t.reserve(static_cast<size_t>(n) + 1);
  for (long k = 1; k <= n; ++k) {
    const double tk = static_cast<double>(k) * output_dt;
    if (tk < t_end * (1 - 1e-12)) t.push_back(tk);
  }
  t.push_back(t_end);
  return t;
}

double max_norm_error(const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return (a - b).lpNorm<Eigen::Infinity>(); }

Measured run_and_measure(const Model& model, std::string_view method, const StepControl& control, double t_end,
                         double output_dt) {
  Measured m;
  m.t_out = output_times(t_end, output_dt);
  StepControl c = control;
  // a large state is summarised at output times, not kept whole
  if (!model.summary_names().empty() && !c.observe) c.observe = [&model](const Eigen::VectorXd& y) { return model.summary(y); };
  m.result = make_integrator(method, c)->integrate(model, 0.0, model.initial_state(), m.t_out);
  measure_error(model, m, t_end);
  return m;
}

Measured least_of_runs(const Model& model, std::string_view method, const StepControl& control, double t_end, int runs) {
  Measured best;
  for (int run = 0; run < runs; ++run) {
    Measured m = run_and_measure(model, method, control, t_end, t_end);
    if (run == 0 || m.result.stats.cpu_seconds < best.result.stats.cpu_seconds) best = std::move(m);
    if (best.result.stats.cpu_seconds > short_run_seconds || best.result.status != Status::ok) break;
  }
  return best;
}

StateSamples sample_states(const Model& model, std::string_view method, StepControl control, double t_end, double interval) {
  StateSamples s{{0.0}, {model.initial_state()}, {}};
  if (!(t_end > 0)) return s;
  control.observe = [](const Eigen::VectorXd& y) { return y; };
  Measured m = run_and_measure(model, method, control, t_end, interval);
  for (size_t k = 0; k < m.result.trajectory.t.size(); ++k) {
    s.t.push_back(m.result.trajectory.t[k]);
    s.y.push_back(std::move(m.result.trajectory.y[k]));
  }
  m.result.trajectory = {};
  s.result = std::move(m.result);
  return s;
}

void measure_error(const Model& model, Measured& m, double t_end) {
  m.error = exact_error(model, m.result, t_end);
  if (!m.error || std::isfinite(*m.error)) return;
  m.result.status = Status::diverged;
  m.result.message = fmt::format("diverged at t = {:.9g}: the error against the exact solution overflowed ({})", t_end, *m.error);
  m.result.t_stop = t_end;
  m.error.reset();
}

std::optional<double> exact_error(const Model& model, const RunResult& result, double t_end) {
  if (result.status != Status::ok || !model.has_exact()) return std::nullopt;
  return max_norm_error(result.y_stop, model.exact(t_end));
}

}  // namespace stepwise
