// Implicit (backward) Euler: y1 = y0 + h f(t0 + h, y1), solved by Newton's method.
//
// G(y1) = y1 - y0 - h f(t1, y1) = 0, G'(y1) = I - h J(t1, y1); each iteration solves
// (I - h J) d = -G and sets y1 += d, until |d|inf <= newton_tol (1 + |y1|inf). The iteration starts
// from y0; the Jacobian is re-evaluated every iteration (full Newton, quadratic convergence).
#include "solvers/fixed_step.hpp"
#include "solvers/mass_spring_implicit.hpp"
#include "solvers/newton_matrix.hpp"
#include "solvers/run_support.hpp"

namespace stepwise {
namespace {

constexpr double newton_tol = 1e-12;  // relative size of the last Newton update; far below any step's truncation error
constexpr int newton_max_iterations = 30;

class ImplicitEuler final : public FixedStepper {
 public:
  explicit ImplicitEuler(const CountedSystem& s)
      : system_(s), matrix_(make_newton_matrix(s)), f_(s.size()), residual_(s.size()), d_(s.size()), y1_(s.size()) {}

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) override {
    const double t1 = t + h;
    y1_ = y;
    for (int iteration = 0; iteration < newton_max_iterations; ++iteration) {
      system_.rhs(t1, y1_, f_);
      residual_ = y + h * f_ - y1_;  // -G(y1)
      if (!matrix_->factor(t1, y1_, h)) {
        failure = fmt::format("implicit-euler: Newton matrix I - hJ singular at t = {:.9g}", t);
        return false;
      }
      matrix_->solve(residual_, d_);
      y1_ += d_;
      if (!y1_.allFinite()) break;
      if (d_.lpNorm<Eigen::Infinity>() <= newton_tol * (1 + y1_.lpNorm<Eigen::Infinity>())) {
        y_next = y1_;
        return true;
      }
    }
    ++system_.stats().rejected;
    failure = fmt::format("implicit-euler: Newton iteration did not converge in {} iterations at t = {:.9g} (h = {:.3g})",
                          newton_max_iterations, t, h);
    return false;
  }

 private:
  const CountedSystem& system_;
  std::unique_ptr<NewtonMatrix> matrix_;
  Eigen::VectorXd f_, residual_, d_, y1_;
};

std::complex<double> implicit_euler_stability(std::complex<double> z) { return 1.0 / (1.0 - z); }

}  // namespace

std::unique_ptr<FixedStepper> make_implicit_euler(const CountedSystem& system) {
  if (system.as<MassSpringView>()) return make_mass_spring_implicit(system, MassSpringImplicitOptions{});
  return std::make_unique<ImplicitEuler>(system);
}

std::unique_ptr<FixedStepper> make_implicit_euler_newton(const CountedSystem& system) {
  if (system.as<MassSpringView>()) {
    MassSpringImplicitOptions options;
    options.newton = true;
    return make_mass_spring_implicit(system, options);
  }
  return std::make_unique<ImplicitEuler>(system);
}

void register_implicit_euler_methods(MethodTable& table) {
  table.add({
      .name = "implicit-euler",
      .family = Family::implicit_euler,
      .source = Source::hand_written,
      .description = "implicit, fixed step; Newton + LU (UMFPACK's sparse LU on a large sparse Jacobian, else dense), or for "
                     "mass-spring systems Baraff-Witkin's linearised step on CHOLMOD (a kept factor preconditioning CG)",
      .order = {1, 1, "1"},
      .stepping = Stepping::fixed,
      .dense = DenseMatrices::unless_mass_spring_or_sparse,
      .make = fixed_steps(make_implicit_euler),
      .stability = {.R = implicit_euler_stability},
  });
  table.add({
      .name = "implicit-euler-newton",
      .family = Family::implicit_euler,
      .source = Source::hand_written,
      .description = "implicit, fixed step, Newton to convergence (CHOLMOD for mass-spring systems, UMFPACK on a large sparse "
                     "Jacobian, else dense LU)",
      .order = {1, 1, "1"},
      .stepping = Stepping::fixed,
      .dense = DenseMatrices::unless_mass_spring_or_sparse,
      .make = fixed_steps(make_implicit_euler_newton),
  });
}

}  // namespace stepwise
