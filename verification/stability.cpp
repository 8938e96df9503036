#include "stability.hpp"

#include "models/height_field.hpp"
#include "solvers/wave_step.hpp"
#include "tolerances.hpp"
#include "wave_modes.hpp"

#include <cmath>
#include <memory>

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

std::function<bool(double dt)> wave_stays_bounded(std::string_view method, int points, double spacing, double c, double mu, long steps) {
  const double middle = spacing * (points - 1) / 2;
  std::shared_ptr<const Model> model =
      make_model("water-drop", {{"size", points}, {"spacing", spacing}, {"c", c}, {"mu", mu}, {"drop_x", middle}, {"drop_y", middle}});
  Eigen::VectorXd y0 = Eigen::VectorXd::Zero(model->size());
  y0.head(static_cast<Eigen::Index>(points) * points) = random_wave_field(points, 1e-3, 11);
  return [model, y0, method = std::string(method), steps](double dt) { return stays_bounded(*model, method, y0, dt, steps); };
}

WaveStability wave_stability(std::string_view method, int points, double spacing, double c, double mu, long steps) {
  const WaveGridView grid{points, spacing, c, mu};
  const double derived = *wave_method_stable_dt(method, grid);
  const double measured = bisect_stability(wave_stays_bounded(method, points, spacing, c, mu, steps), 0.5 * derived, 2 * derived,
                                           tolerance::stability_bisection_width);
  return {measured, derived, seeds_wave_condition(grid)};
}

}  // namespace stepwise
