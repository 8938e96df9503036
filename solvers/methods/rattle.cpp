// rattle: RATTLE (Andersen 1983; Hairer, Lubich & Wanner, Geometric Numerical Integration, VII.1), the
// constrained Störmer-Verlet method on particles held by distance constraints (the DistanceConstraints
// capability): symplectic, second order, on the constraint manifold. With a = the external acceleration,
// G = the constraints' gradients and w the inverse masses:
//   v+ = v0 + h/2 (a(x0) + w G(x0)^T lambda),  x1 = x0 + h v+,   g(x1) = 0         (SHAKE: lambda)
//   v1 = v+ + h/2 (a(x1) + w G(x1)^T mu),                        G(x1) v1 = 0      (mu)
// Each multiplier found by Gauss-Seidel sweeps over the constraints, each a Newton step along its own gradient,
// to rounding (the sweeps stop when no constraint is off by more than a few eps of its length).
#include "solvers/capabilities/distance_constraints.hpp"
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
      : system_(s), c_(*s.as<DistanceConstraints>()), n_(s.size() / 2), a_(n_), gradient0_(c_.constraints.size() * 3) {}

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& message) override {
    const int d = c_.dimension;
    y_next = y;
    double* x = y_next.data();
    double* v = x + n_;
    // the constraints' directions at the step's start, along which SHAKE moves the positions
    for (size_t j = 0; j < c_.constraints.size(); ++j) c_.violation(c_.constraints[j], y.data(), &gradient0_[3 * j]);
    kick(t, h / 2, x, v);
    for (Eigen::Index i = 0; i < n_; ++i) x[i] += h * v[i];
    // SHAKE: x1 back onto g = 0 along w G(x0)^T, the velocity v+ = (x1 - x0) / h moving with it
    if (!sweep([&](const DistanceConstraint& c, size_t j, double* n1) {
          const double C = c_.violation(c, x, n1);
          const double* n0 = &gradient0_[3 * j];
          double along = 0;
          for (int k = 0; k < d; ++k) along += n1[k] * n0[k];
          const double w = weight(c), delta = along * w != 0 ? -C / (w * along) : 0.0;
          move(c, x, n0, delta);
          move(c, v, n0, delta / h);
          return std::abs(C) / c.length;
        })) {
      message = fmt::format("rattle: the position constraints did not converge in {} sweeps at t = {}", max_sweeps, t);
      return false;
    }
    kick(t + h, h / 2, x, v);
    // the velocity onto G(x1) v = 0
    if (!sweep([&](const DistanceConstraint& c, size_t, double* n1) {
          c_.violation(c, x, n1);
          double along = 0;
          for (int k = 0; k < d; ++k) along += n1[k] * (v[c.a * d + k] - (c.b < 0 ? 0.0 : v[c.b * d + k]));
          const double w = weight(c);
          if (w > 0) move(c, v, n1, -along / w);
          return std::abs(along) * h / c.length;
        })) {
      message = fmt::format("rattle: the velocity constraints did not converge in {} sweeps at t = {}", max_sweeps, t);
      return false;
    }
    RunningNorm norm;
    for (Eigen::Index i = 0; i < y_next.size(); ++i) norm.add(y_next[i]);
    norm_ = norm.value();
    return true;
  }

 private:
  static constexpr int max_sweeps = 1000;
  static constexpr double converged = 4 * std::numeric_limits<double>::epsilon();

  // Gauss-Seidel sweeps of `project` (constraint, its index, scratch for its direction -> its relative error
  // before the update) until every constraint is within `converged` in one sweep; false if none is
  template <class Project>
  bool sweep(const Project& project) {
    double n1[3];
    for (int s = 0; s < max_sweeps; ++s) {
      double worst = 0;
      for (size_t j = 0; j < c_.constraints.size(); ++j) worst = std::max(worst, project(c_.constraints[j], j, n1));
      if (worst <= converged) return true;
    }
    return false;
  }
  // v += dt a(x, v), on the particles that move
  void kick(double t, double dt, const double* x, double* v) {
    c_.external(t, x, v, a_.data());
    ++system_.stats().rhs_evals;
    for (Eigen::Index i = 0; i < n_; ++i)
      if (c_.inverse_mass[static_cast<size_t>(i / c_.dimension)] > 0) v[i] += dt * a_[i];
  }
  double weight(const DistanceConstraint& c) const {
    return c_.inverse_mass[static_cast<size_t>(c.a)] + (c.b < 0 ? 0.0 : c_.inverse_mass[static_cast<size_t>(c.b)]);
  }
  // z_a += w_a s n, z_b -= w_b s n (positions or velocities)
  void move(const DistanceConstraint& c, double* z, const double* n, double s) const {
    const int d = c_.dimension;
    for (int k = 0; k < d; ++k) {
      z[c.a * d + k] += c_.inverse_mass[static_cast<size_t>(c.a)] * s * n[k];
      if (c.b >= 0) z[c.b * d + k] -= c_.inverse_mass[static_cast<size_t>(c.b)] * s * n[k];
    }
  }

  const CountedSystem& system_;
  const DistanceConstraints& c_;
  Eigen::Index n_;
  Eigen::VectorXd a_;
  std::vector<double> gradient0_;  // each constraint's unit direction at the step's start, 3 entries each
};

}  // namespace

void register_rattle_methods(MethodTable& table) {
  table.add({
      .name = "rattle",
      .family = "constrained",
      .source = "hand-written",
      .description = "RATTLE (Andersen 1983): constrained Störmer-Verlet, symplectic and on the constraint manifold; constrained scenes only",
      .order = {2, 2, "2"},
      .stepping = Stepping::fixed,
      .needs = needs_distance_constraints,
      .make = fixed_steps([](const CountedSystem& system) { return std::make_unique<Rattle>(system); }),
  });
}

}  // namespace stepwise
