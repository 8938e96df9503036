#include "stability.hpp"

#include "models/hanging_chain.hpp"
#include "models/height_field.hpp"
#include "solvers/capabilities/mass_spring.hpp"
#include "solvers/fd_jacobian.hpp"
#include "solvers/stability.hpp"
#include "solvers/wave_step.hpp"
#include "tolerances.hpp"
#include "wave_modes.hpp"

#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
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
  const double derived = find_method(method)->stability.wave_dt(grid);
  const double measured = bisect_stability(wave_stays_bounded(method, points, spacing, c, mu, steps), 0.5 * derived, 2 * derived,
                                           tolerance::stability_bisection_width);
  return {measured, derived, seeds_wave_condition(grid)};
}

std::optional<double> mass_spring_stable_dt(std::string_view method, const StiffestMode& mode) {
  const Method* m = find_method(method);
  if (!m || !m->stability.oscillator_dt) return std::nullopt;
  return m->stability.oscillator_dt(mode.omega, mode.damping);
}

double measured_stable_dt(const Model& model, std::string_view method, long steps, double predicted) {
  const Eigen::VectorXd y0 = model.initial_state();
  const auto bounded = [&](double dt) { return stays_bounded(model, method, y0, dt, steps); };
  const double low = predicted > 0 ? predicted / 10 : 1e-6, high = predicted > 0 ? predicted * 10 : 1;
  return bisect_stability(bounded, low, high, tolerance::stability_bisection_width);
}

std::optional<std::complex<double>> stability_function(std::string_view method, std::complex<double> z) {
  const Method* m = find_method(method);
  if (!m || !m->stability.R) return std::nullopt;
  return m->stability.R(z);
}

namespace {

// y' = z y in real pairs: y = (Re, Im), f = (a y0 - b y1, b y0 + a y1)
class ComplexScalar final : public OdeSystem, public DenseJacobian {
 public:
  explicit ComplexScalar(std::complex<double> z) : z_(z) {}
  int size() const override { return 2; }
  bool autonomous() const override { return true; }
  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) const override {
    f[0] = z_.real() * y[0] - z_.imag() * y[1];
    f[1] = z_.imag() * y[0] + z_.real() * y[1];
  }
  void jacobian(double, const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::MatrixXd> j) const override {
    j << z_.real(), -z_.imag(), z_.imag(), z_.real();
  }
  const void* capability(const std::type_info& type) const override { return offer(type, as_part<DenseJacobian>(*this)); }

 private:
  std::complex<double> z_;
};

}  // namespace

std::optional<std::function<std::complex<double>(std::complex<double>)>> measured_stability_function(const Method& method) {
  if (!method.fixed_step() || method.needs.type || method.order.min != method.order.max || method.family == Family::gpu) return std::nullopt;
  const Method* m = &method;
  return [m](std::complex<double> z) {
    const ComplexScalar system(z);
    const std::vector<double> times{1.0};
    const RunResult r = make_integrator(m->name, StepControl::fixed(1.0))->integrate(system, 0, Eigen::Vector2d(1, 0), times);
    if (r.status != Status::ok || r.trajectory.y.empty()) return std::complex<double>(std::numeric_limits<double>::infinity(), 0);
    return std::complex<double>(r.trajectory.y.back()[0], r.trajectory.y.back()[1]);
  };
}

std::optional<double> predicted_stable_dt(const Method& method, const Eigen::VectorXcd& eigenvalues) {
  if (eigenvalues.size() == 0) return std::nullopt;
  if (method.stability.R) return largest_stable_step(method.stability.R, eigenvalues);
  if (const auto R = measured_stability_function(method)) return largest_stable_step(*R, eigenvalues);
  return std::nullopt;
}

Eigen::VectorXcd jacobian_spectrum(const OdeSystem& system, double t, const Eigen::VectorXd& y) {
  Eigen::MatrixXd j(system.size(), system.size());
  jacobian_or_fd(system, t, y, j);
  return dense_eigenvalues(j);
}

std::optional<double> spectrum_stable_dt(std::string_view method, const Eigen::VectorXcd& eigenvalues) {
  const Method* m = find_method(method);
  if (!m || !m->stability.R || eigenvalues.size() == 0) return std::nullopt;
  return largest_stable_step(m->stability.R, eigenvalues);
}

std::unique_ptr<Model> stability_sheet(double stiffness) {
  return make_model("cloth", {{"rows", 8}, {"columns", 8}, {"stiffness", stiffness}, {"shear_stiffness", stiffness / 2},
                              {"bend_stiffness", stiffness / 10}, {"wind_coefficient", 0}, {"pin_corners", 0}, {"pin_top_corners", 1}});
}

std::vector<double> implicit_euler_amplitude_ratios(double wh, int steps) {
  const double mass = 0.1, stiffness = 40, g = 9.81, w = std::sqrt(stiffness / mass);
  const auto spring = make_model("hanging-chain", {{"nodes", 1}, {"mass", mass}, {"stiffness", stiffness}, {"damping", 0}, {"g", g}});
  const double rest = chain_equilibrium(1, mass, stiffness, spring->as<MassSpringView>()->springs[0].rest, g)[0];
  const auto amplitude = [&](const Eigen::VectorXd& y) { return std::hypot(w * (y[1] - rest), y[4]); };
  const double h = wh / w;
  std::vector<double> times;
  for (int k = 1; k <= steps; ++k) times.push_back(k * h);
  const RunResult r = make_integrator("implicit-euler", StepControl::fixed(h))->integrate(*spring, 0, spring->initial_state(), times);
  std::vector<double> ratios;
  double before = amplitude(spring->initial_state());
  for (const auto& y : r.trajectory.y) {
    ratios.push_back(amplitude(y) / before);
    before = amplitude(y);
  }
  return ratios;
}

}  // namespace stepwise
