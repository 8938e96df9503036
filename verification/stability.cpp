#include "stability.hpp"

#include <cmath>

namespace stepwise {

double bisect_stability(const std::function<bool(double dt)>& is_stable, double stable, double unstable, double rel_width) {
  while (unstable - stable > rel_width * stable) {
    const double middle = (stable + unstable) / 2;
    (is_stable(middle) ? stable : unstable) = middle;
  }
  return stable;
}

bool stays_bounded(const OdeSystem& system, std::string_view method, const Eigen::VectorXd& y0, double dt, long steps) {
  StepControl control = StepControl::fixed(dt);
  control.blowup = 1e6 * y0.lpNorm<Eigen::Infinity>();
  const std::vector<double> t_out{static_cast<double>(steps) * dt};
  return make_integrator(method, control)->integrate(system, 0, y0, t_out).status == Status::ok;
}

double seeds_wave_condition(const WaveGridView& grid) {
  const double r = grid.c * grid.c / (grid.spacing * grid.spacing);
  return (grid.mu + std::sqrt(grid.mu * grid.mu + 32 * r)) / (8 * r);
}

}  // namespace stepwise
