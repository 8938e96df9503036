// rattle: RATTLE (Andersen 1983; Hairer, Lubich & Wanner, Geometric Numerical Integration, VII.1), the
// constrained Störmer-Verlet method on particles held by distance constraints (the DistanceConstraints
// capability): symplectic, second order, on the constraint manifold. With a = the external acceleration,
// G = the constraints' gradients and w the inverse masses:
//   v+ = v0 + h/2 (a(x0) + w G(x0)^T lambda),  x1 = x0 + h v+,   g(x1) = 0         (SHAKE: lambda)
//   v1 = v+ + h/2 (a(x1) + w G(x1)^T mu),                        G(x1) v1 = 0      (mu)
// lambda by Newton's method on g(x1) = 0 (each iteration one sparse LU of G(x1) W G(x0)^T: a chain's links
// couple along it, which Gauss-Seidel sweeps would take ~N^2 sweeps to settle) to the rounding of the
// coordinates; mu by one solve of the linear G(x1) W G(x1)^T mu = -G(x1) v.
#include "solvers/capabilities/distance_constraints.hpp"
#include "solvers/fixed_step.hpp"
#include "solvers/method_table.hpp"
#include "solvers/run_support.hpp"

#include <Eigen/SparseCore>
#include <Eigen/LU>
#include <Eigen/SparseLU>
#include <fmt/format.h>

#include <cmath>
#include <limits>

namespace stepwise {
namespace {

// one unit direction a row (3 entries, `dimension` used and the rest 0), each row contiguous for
// DistanceConstraints::violation
using Directions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

class Rattle final : public PlainStepping<Rattle> {
 public:
  static constexpr int size = 0;  // PlainStepping: no advance(), the state of a run-time size

  explicit Rattle(const CountedSystem& s)
      : system_(s), c_(*s.as<DistanceConstraints>()), n_(s.size() / 2), m_(static_cast<Eigen::Index>(c_.constraints.size())), a_(n_),
        n0_(Directions::Zero(m_, 3)), n1_(Directions::Zero(m_, 3)), touching_(static_cast<size_t>(c_.particles())) {
    for (size_t j = 0; j < c_.constraints.size(); ++j) {
      touching_[static_cast<size_t>(c_.constraints[j].a)].push_back({static_cast<int>(j), 1.0});
      if (c_.constraints[j].b >= 0) touching_[static_cast<size_t>(c_.constraints[j].b)].push_back({static_cast<int>(j), -1.0});
    }
  }

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& message) override {
    y_next = y;
    double* x = y_next.data();
    double* v = x + n_;
    directions(y.data(), n0_);  // the gradients at the step's start, along which SHAKE moves the positions
    kick(t, h / 2, x, v);
    for (Eigen::Index i = 0; i < n_; ++i) x[i] += h * v[i];
    // SHAKE: Newton on g(x1 + W G(x0)^T dlambda) = 0, the velocity v+ = (x1 - x0) / h moving with the positions
    Eigen::VectorXd C(m_);
    for (int k = 0;; ++k) {
      double worst = 0;
      for (Eigen::Index j = 0; j < m_; ++j) {
        const DistanceConstraint& c = c_.constraints[static_cast<size_t>(j)];
        C[j] = c_.violation(c, x, &n1_(j, 0));
        worst = std::max(worst, std::abs(C[j]) / (c.length + magnitude(c, x)));
      }
      if (worst <= converged) break;
      if (k == max_newton) {
        message = fmt::format("rattle: SHAKE's Newton iteration did not meet the constraints in {} iterations at t = {} (off by {:.3g})", max_newton, t, worst);
        return false;
      }
      const Eigen::VectorXd dlambda = solve(n1_, n0_, -C);
      if (!dlambda.allFinite()) {
        message = fmt::format("rattle: the constraints' Jacobian is singular at t = {}", t);
        return false;
      }
      move(x, n0_, dlambda);
      move(v, n0_, dlambda / h);
    }
    kick(t + h, h / 2, x, v);
    // the velocity onto G(x1) v = 0: one linear solve (n1_ holds the constraints' directions at x1)
    Eigen::VectorXd along(m_);
    for (Eigen::Index j = 0; j < m_; ++j) {
      const DistanceConstraint& c = c_.constraints[static_cast<size_t>(j)];
      along[j] = 0;
      for (int k = 0; k < c_.dimension; ++k) along[j] += n1_(j, k) * (v[c.a * c_.dimension + k] - (c.b < 0 ? 0.0 : v[c.b * c_.dimension + k]));
    }
    move(v, n1_, solve(n1_, n1_, -along));
    RunningNorm norm;
    for (Eigen::Index i = 0; i < y_next.size(); ++i) norm.add(y_next[i]);
    norm_ = norm.value();
    return true;
  }

 private:
  static constexpr int max_newton = 50;
  static constexpr Eigen::Index dense_below = 64;
  // a constraint is met when it is off by no more than the rounding of the coordinates it is computed from: a
  // few eps of the link's length plus its ends' magnitudes (a link of 5 cm at a metre from the pin is computed
  // from coordinates rounded to 1e-16 m, 2e-15 of the link)
  static constexpr double converged = 8 * std::numeric_limits<double>::epsilon();

  // each constraint's unit direction at x (a row each)
  void directions(const double* x, Directions& n) const {
    for (Eigen::Index j = 0; j < m_; ++j) c_.violation(c_.constraints[static_cast<size_t>(j)], x, &n(j, 0));
  }
  // the multipliers' system (G(u) W G(w)^T) z = r, G's rows the constraints' directions u and w (+ at a, - at b):
  // a constraint couples only the constraints sharing a particle with it. Up to dense_below constraints by
  // Eigen's dense LU (a pendulum's one: a sparse factorisation's setup cost 20 times the step), else its sparse LU
  Eigen::VectorXd solve(const Directions& u, const Directions& w, const Eigen::VectorXd& r) {
    std::vector<Eigen::Triplet<double>> entries;
    for (size_t p = 0; p < touching_.size(); ++p) {
      const double inverse_mass = c_.inverse_mass[p];
      if (inverse_mass == 0) continue;
      for (const auto& [j, sj] : touching_[p])
        for (const auto& [k, sk] : touching_[p]) entries.emplace_back(j, k, sj * sk * inverse_mass * u.row(j).dot(w.row(k)));
    }
    if (m_ <= dense_below) {
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m_, m_);
      for (const auto& e : entries) A(e.row(), e.col()) += e.value();
      return A.partialPivLu().solve(r);
    }
    // the pattern never changes (which constraints share a particle): ordered and analysed once, factorised anew
    A_.setFromTriplets(entries.begin(), entries.end());
    if (!analysed_) lu_.analyzePattern(A_), analysed_ = true;
    lu_.factorize(A_);
    if (lu_.info() != Eigen::Success) return Eigen::VectorXd::Constant(m_, std::numeric_limits<double>::quiet_NaN());
    return lu_.solve(r);
  }
  // z += W G^T s, G's rows the directions n (positions or velocities)
  void move(double* z, const Directions& n, const Eigen::VectorXd& s) const {
    const int d = c_.dimension;
    for (Eigen::Index j = 0; j < m_; ++j) {
      const DistanceConstraint& c = c_.constraints[static_cast<size_t>(j)];
      for (int k = 0; k < d; ++k) {
        z[c.a * d + k] += c_.inverse_mass[static_cast<size_t>(c.a)] * s[j] * n(j, k);
        if (c.b >= 0) z[c.b * d + k] -= c_.inverse_mass[static_cast<size_t>(c.b)] * s[j] * n(j, k);
      }
    }
  }
  // |x_a|inf + |x_b|inf: the scale a constraint's rounding goes with
  double magnitude(const DistanceConstraint& c, const double* z) const {
    double m = 0;
    for (int k = 0; k < c_.dimension; ++k) {
      m = std::max(m, std::abs(z[c.a * c_.dimension + k]));
      if (c.b >= 0) m = std::max(m, std::abs(z[c.b * c_.dimension + k]));
    }
    return 2 * m;
  }
  // v += dt a(x, v), on the particles that move
  void kick(double t, double dt, const double* x, double* v) {
    c_.external(t, x, v, a_.data());
    ++system_.stats().rhs_evals;
    for (Eigen::Index i = 0; i < n_; ++i)
      if (c_.inverse_mass[static_cast<size_t>(i / c_.dimension)] > 0) v[i] += dt * a_[i];
  }

  const CountedSystem& system_;
  const DistanceConstraints& c_;
  Eigen::Index n_, m_;  // coordinates; constraints
  Eigen::VectorXd a_;
  Directions n0_, n1_;  // the constraints' directions at the step's start and at x1
  std::vector<std::vector<std::pair<int, double>>> touching_;  // a particle's constraints, with the sign of its end
  Eigen::SparseMatrix<double> A_{m_, m_};  // the multipliers' system, above dense_below constraints
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu_;
  bool analysed_ = false;
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
