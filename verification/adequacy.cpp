#include "adequacy.hpp"

#include "models/model.hpp"
#include "models/pendulum.hpp"
#include "solvers/method_table.hpp"

#include <cmath>
#include <numbers>

namespace stepwise {

double small_angle_phase_error(double theta0, double n_periods) {
  // g and L cancel in T/T0; any positive values do
  const double ratio = pendulum_period(theta0, 1.0, 1.0) / (2 * std::numbers::pi);
  return 2 * std::numbers::pi * n_periods * (ratio - 1);
}

double small_angle_max_amplitude(double phase_tolerance, double n_periods) {
  // the phase error grows monotonically with amplitude on (0, pi)
  double lo = 0, hi = std::numbers::pi - 1e-6;  // K(k) is finite for k = sin(theta0/2) < 1
  if (small_angle_phase_error(hi, n_periods) <= phase_tolerance) return hi;
  for (int i = 0; i < 100 && hi - lo > 1e-14; ++i) {
    const double mid = 0.5 * (lo + hi);
    (small_angle_phase_error(mid, n_periods) <= phase_tolerance ? lo : hi) = mid;
  }
  return lo;
}

LinearWaveDeparture linear_wave_departure(double amplitude_over_depth, const LinearWaveSetup& setup) {
  const double middle = (setup.size - 1) * setup.spacing / 2;
  const Params drop{{"size", setup.size}, {"spacing", setup.spacing}, {"mu", setup.mu}, {"drop_x", middle}, {"drop_y", middle},
                    {"drop_radius", setup.radius}, {"drop_height", amplitude_over_depth * setup.depth}};
  Params wave = drop, shallow = drop;
  wave["c"] = std::sqrt(setup.g * setup.depth);
  shallow["depth"] = setup.depth;
  shallow["g"] = setup.g;
  const std::vector<double> t_out{setup.t_end};
  const Eigen::Index cells = static_cast<Eigen::Index>(setup.size) * setup.size;
  const auto run = [&](const char* name, const Params& p) {
    const auto model = make_model(name, p);
    return make_integrator("rk4", StepControl::fixed(setup.dt))->integrate(*model, 0, model->initial_state(), t_out).y_stop.head(cells).eval();
  };
  LinearWaveDeparture d;
  d.wave = run("water-drop", wave);
  d.shallow = run("shallow-water", shallow);
  d.relative = (d.shallow - d.wave).norm() / d.wave.norm();
  d.relative_max = (d.shallow - d.wave).cwiseAbs().maxCoeff() / d.wave.cwiseAbs().maxCoeff();
  return d;
}

}  // namespace stepwise
