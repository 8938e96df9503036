// rattle: RATTLE (Andersen 1983; Hairer, Lubich & Wanner, Geometric Numerical Integration, VII.1), the
// constrained Störmer-Verlet method on particles held by distance constraints (the DistanceConstraints
// capability): symplectic, second order, on the constraint manifold. With a = the external acceleration,
// G = the constraints' gradients and w the inverse masses:
//   v+ = v0 + h/2 (a(x0) + w G(x0)^T lambda),  x1 = x0 + h v+,   g(x1) = 0         (SHAKE: lambda)
//   v1 = v+ + h/2 (a(x1) + w G(x1)^T mu),                        G(x1) v1 = 0      (mu)
// lambda by Newton's method on g(x1) = 0, mu by one linear solve (solvers/constraint_solver.hpp: Gauss-Seidel
// sweeps over a chain's links would take ~N^2 sweeps to settle what an LU does at once). A compliant constraint
// (alpha > 0) is a spring: its force joins a's, and SHAKE meets the rigid ones alone.
#include "solvers/constraint_solver.hpp"
#include "solvers/fixed_step.hpp"
#include "solvers/method_table.hpp"
#include "solvers/run_support.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

namespace stepwise {
namespace {

class Rattle final : public PlainStepping<Rattle> {
 public:
  static constexpr int size = 0;  // PlainStepping: no advance(), the state of a run-time size

  explicit Rattle(const CountedSystem& s)
      : system_(s), c_(*s.as<DistanceConstraints>()), rigid_(c_.rigid()), solver_(rigid_), n_(s.size() / 2), a_(n_) {}

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& message) override {
    y_next = y;
    double* x = y_next.data();
    double* v = x + n_;
    solver_.directions(y.data(), n0_);  // the gradients at the step's start, along which SHAKE moves the positions
    kick(t, h / 2, x, v);
    for (Eigen::Index i = 0; i < n_; ++i) x[i] += h * v[i];
    // SHAKE: Newton on g(x1 + W G(x0)^T dlambda) = 0, the velocity v+ = (x1 - x0) / h moving with the positions
    if (std::string why; !solver_.meet(x, n0_, v, h, why)) {
      message = fmt::format("rattle: SHAKE at t = {}: {}", t, why);
      return false;
    }
    kick(t + h, h / 2, x, v);
    solver_.tangent(v);  // onto G(x1) v = 0
    RunningNorm norm;
    for (Eigen::Index i = 0; i < y_next.size(); ++i) norm.add(y_next[i]);
    norm_ = norm.value();
    return true;
  }

 private:
  // v += dt a(x, v), on the particles that move: the external acceleration and the compliant constraints'
  // springs (Störmer-Verlet's kick)
  void kick(double t, double dt, const double* x, double* v) {
    c_.external(t, x, v, a_.data());
    c_.add_compliant_forces(x, a_.data());
    ++system_.stats().rhs_evals;
    for (Eigen::Index i = 0; i < n_; ++i)
      if (c_.inverse_mass[static_cast<size_t>(i / c_.dimension)] > 0) v[i] += dt * a_[i];
  }

  const CountedSystem& system_;
  const DistanceConstraints& c_;
  DistanceConstraints rigid_;  // the constraints SHAKE and the tangent step meet; the compliant ones are forces
  ConstraintSolver solver_;
  Eigen::Index n_;
  Eigen::VectorXd a_;
  Directions n0_;  // the constraints' directions at the step's start
};

}  // namespace

void register_rattle_methods(MethodTable& table) {
  table.add({
      .name = "rattle",
      .family = Family::constrained,
      .source = Source::hand_written,
      .description = "RATTLE (Andersen 1983): constrained Störmer-Verlet, symplectic and on the constraint manifold; constrained scenes only",
      .order = {2, 2, "2"},
      .stepping = Stepping::fixed,
      .needs = needs_distance_constraints,
      .make = fixed_steps([](const CountedSystem& system) { return std::make_unique<Rattle>(system); }),
  });
}

}  // namespace stepwise
