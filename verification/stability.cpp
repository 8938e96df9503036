#include "stability.hpp"

#include "models/hanging_chain.hpp"
#include "models/height_field.hpp"
#include "solvers/fd_jacobian.hpp"
#include "solvers/wave_step.hpp"
#include "tolerances.hpp"
#include "wave_modes.hpp"

#include <Eigen/Eigenvalues>

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
  const double derived = *wave_method_stable_dt(method, grid);
  const double measured = bisect_stability(wave_stays_bounded(method, points, spacing, c, mu, steps), 0.5 * derived, 2 * derived,
                                           tolerance::stability_bisection_width);
  return {measured, derived, seeds_wave_condition(grid)};
}

StiffestMode stiffest_mode(const OdeSystem& system, double t, const Eigen::VectorXd& y) {
  const MassSpringView* view = system.mass_spring();
  if (!view) throw std::invalid_argument("stiffest_mode: not a mass-spring system");
  Eigen::SparseMatrix<double> k, d;
  system.force_jacobians(t, y, false, k, d);
  const Eigen::Index n = k.rows();
  Eigen::VectorXd root_mass(n);
  for (int i = 0; i < view->nodes; ++i) root_mass.segment<3>(3 * i).setConstant(std::sqrt(view->mass[i]));
  const Eigen::VectorXd inverse = root_mass.cwiseInverse();
  // S = M^-1/2 (-K) M^-1/2, symmetric for the springs' K (the wind's position part, not symmetric, is taken
  // symmetrised)
  Eigen::SparseMatrix<double> s = -(inverse.asDiagonal() * k * inverse.asDiagonal());
  s = (Eigen::SparseMatrix<double>(s.transpose()) + s) / 2;
  Eigen::VectorXd mode(n);
  double lambda = 0;
  if (n <= 3000) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen{Eigen::MatrixXd(s)};
    lambda = eigen.eigenvalues()[n - 1];
    mode = eigen.eigenvectors().col(n - 1);
  } else {
    mode = Eigen::VectorXd::LinSpaced(n, 1, 2);
    for (int k = 0; k < 400; ++k) mode = (s * mode).normalized();
    lambda = mode.dot(s * mode);
  }
  const Eigen::VectorXd v = inverse.cwiseProduct(mode);  // the mode in coordinates: M^-1/2 times S's eigenvector
  const double a = -v.dot(d * v) / (2 * v.dot(root_mass.cwiseAbs2().cwiseProduct(v)));
  return {std::sqrt(std::max(lambda, 0.0)), a};
}

std::optional<double> mass_spring_stable_dt(std::string_view method, const StiffestMode& mode) {
  const double w = mode.omega, a = mode.damping;
  // symplectic Euler on x'' = -w^2 x - 2 a x': amplification [[1 - h^2 w^2, h (1 - 2 h a)], [-h w^2, 1 - 2 h a]],
  // determinant 1 - 2 h a, trace 2 - h^2 w^2 - 2 h a; |trace| <= 1 + determinant gives h^2 w^2 <= 4 - 4 h a
  if (method == "symplectic-euler" || method == "gpu-cloth") return 2 * (std::sqrt(a * a + w * w) - a) / (w * w);
  // explicit Euler and rk4: |R(h lambda)| <= 1 at lambda = -a + i sqrt(w^2 - a^2), |lambda| = w
  const std::complex<double> lambda(-a, std::sqrt(std::max(w * w - a * a, 0.0)));
  if (method == "euler") return 2 * a / (w * w);
  // rk4 has no closed form: the step where |R(h lambda)| reaches 1 on the mode's pair of eigenvalues
  if (method == "rk4") return spectrum_stable_dt(method, Eigen::Vector2cd(lambda, std::conj(lambda)));
  return std::nullopt;
}

double measured_stable_dt(const Model& model, std::string_view method, long steps, double predicted) {
  const Eigen::VectorXd y0 = model.initial_state();
  const auto bounded = [&](double dt) { return stays_bounded(model, method, y0, dt, steps); };
  const double low = predicted > 0 ? predicted / 10 : 1e-6, high = predicted > 0 ? predicted * 10 : 1;
  return bisect_stability(bounded, low, high, tolerance::stability_bisection_width);
}

std::optional<std::complex<double>> stability_function(std::string_view method, std::complex<double> z) {
  if (method == "euler") return 1.0 + z;
  if (method == "rk4") return 1.0 + z * (1.0 + z / 2.0 * (1.0 + z / 3.0 * (1.0 + z / 4.0)));
  if (method == "implicit-euler") return 1.0 / (1.0 - z);
  return std::nullopt;
}

Eigen::VectorXcd jacobian_spectrum(const OdeSystem& system, double t, const Eigen::VectorXd& y) {
  Eigen::MatrixXd j(system.size(), system.size());
  jacobian_or_fd(system, t, y, j);
  return Eigen::EigenSolver<Eigen::MatrixXd>(j, false).eigenvalues();
}

std::optional<double> spectrum_stable_dt(std::string_view method, const Eigen::VectorXcd& eigenvalues) {
  if (!stability_function(method, 0) || eigenvalues.size() == 0) return std::nullopt;
  // the spectrum is as accurate as the Jacobian: a difference Jacobian's relative error is ~sqrt(machine
  // epsilon) = 1.5e-8, so an eigenvalue on the imaginary axis (an undamped mode) may come out with a positive real
  // part of that order of the largest |lambda|, and a zero (a fixed boundary value, an invariant) as a speck of
  // that size. Real parts up to this fraction of the largest are taken as 0, and eigenvalues smaller than it are
  // left out: R(0) = 1 for every consistent method, so zeros never grow.
  constexpr double jacobian_resolution = 1e-6;
  // what remains is exact to round-off: this much growth per step is taken as none
  constexpr double spectrum_growth_allowance = 1e-9;
  const double largest = eigenvalues.cwiseAbs().maxCoeff();
  std::vector<std::complex<double>> spectrum;
  for (const auto& lambda : eigenvalues)
    if (std::abs(lambda) > jacobian_resolution * largest)
      spectrum.emplace_back(lambda.real() > 0 && lambda.real() < jacobian_resolution * largest ? 0.0 : lambda.real(), lambda.imag());
  const auto grows = [&](double h) {
    for (const auto& lambda : spectrum)
      if (std::abs(*stability_function(method, h * lambda)) > 1 + spectrum_growth_allowance) return true;
    return false;
  };
  double smallest = largest;
  for (const auto& lambda : spectrum) smallest = std::min(smallest, std::abs(lambda));
  double low = 1e-3 / largest;
  if (grows(low)) return 0.0;
  double high = 2 * low;
  while (!grows(high)) {
    low = high;
    high *= 2;
    if (low > 1e6 / smallest) return std::numeric_limits<double>::infinity();
  }
  while (high - low > 1e-9 * high) (grows((low + high) / 2) ? high : low) = (low + high) / 2;
  return low;
}

std::unique_ptr<Model> stability_sheet(double stiffness) {
  return make_model("cloth", {{"rows", 8}, {"columns", 8}, {"stiffness", stiffness}, {"shear_stiffness", stiffness / 2},
                              {"bend_stiffness", stiffness / 10}, {"wind_coefficient", 0}, {"pin_corners", 0}, {"pin_top_corners", 1}});
}

std::vector<double> implicit_euler_amplitude_ratios(double wh, int steps) {
  const double mass = 0.1, stiffness = 40, g = 9.81, w = std::sqrt(stiffness / mass);
  const auto spring = make_model("hanging-chain", {{"nodes", 1}, {"mass", mass}, {"stiffness", stiffness}, {"damping", 0}, {"g", g}});
  const double rest = chain_equilibrium(1, mass, stiffness, spring->mass_spring()->springs[0].rest, g)[0];
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
