#include "constraint_solver.hpp"

#include <Eigen/LU>
#include <fmt/format.h>

#include <cmath>
#include <limits>

namespace stepwise {
namespace {

constexpr int max_newton = 50;
// up to this many constraints the multipliers' system is solved by Eigen's dense LU (a pendulum's one: a sparse
// factorisation's set-up cost 20 times the step), above by its sparse LU
constexpr Eigen::Index dense_below = 64;
// a constraint is met when it is off by no more than the rounding of the coordinates it is computed from: a few
// eps of the link's length plus its ends' magnitudes (a link of 5 cm at a metre from the pin is computed from
// coordinates rounded to 1e-16 m, 2e-15 of the link)
constexpr double converged = 8 * std::numeric_limits<double>::epsilon();

}  // namespace

ConstraintSolver::ConstraintSolver(const DistanceConstraints& c)
    : c_(c), m_(static_cast<Eigen::Index>(c.constraints.size())), n1_(Directions::Zero(m_, 3)),
      touching_(static_cast<size_t>(c.particles())), A_(m_, m_) {
  for (size_t j = 0; j < c_.constraints.size(); ++j) {
    touching_[static_cast<size_t>(c_.constraints[j].a)].push_back({static_cast<int>(j), 1.0});
    if (c_.constraints[j].b >= 0) touching_[static_cast<size_t>(c_.constraints[j].b)].push_back({static_cast<int>(j), -1.0});
  }
}

void ConstraintSolver::directions(const double* x, Directions& n) const {
  n.setZero(m_, 3);
  for (Eigen::Index j = 0; j < m_; ++j) c_.violation(c_.constraints[static_cast<size_t>(j)], x, &n(j, 0));
}

bool ConstraintSolver::meet(double* x, const Directions& along, double* v, double h, std::string& why) {
  Eigen::VectorXd C(m_);
  for (int k = 0;; ++k) {
    double worst = 0;
    for (Eigen::Index j = 0; j < m_; ++j) {
      const DistanceConstraint& c = c_.constraints[static_cast<size_t>(j)];
      C[j] = c_.violation(c, x, &n1_(j, 0));
      worst = std::max(worst, std::abs(C[j]) / (c.length + magnitude(c, x)));
    }
    if (worst <= converged) return true;
    if (k == max_newton) {
      why = fmt::format("Newton's iteration did not meet the constraints in {} iterations (off by {:.3g})", max_newton, worst);
      return false;
    }
    const Eigen::VectorXd dlambda = solve(n1_, along, -C);
    if (!dlambda.allFinite()) {
      why = "the constraints' Jacobian is singular";
      return false;
    }
    move(x, along, dlambda);
    if (v) move(v, along, dlambda / h);
  }
}

void ConstraintSolver::tangent(double* v) {
  Eigen::VectorXd rate(m_);
  const int d = c_.dimension;
  for (Eigen::Index j = 0; j < m_; ++j) {
    const DistanceConstraint& c = c_.constraints[static_cast<size_t>(j)];
    rate[j] = 0;
    for (int k = 0; k < d; ++k) rate[j] += n1_(j, k) * (v[c.a * d + k] - (c.b < 0 ? 0.0 : v[c.b * d + k]));
  }
  move(v, n1_, solve(n1_, n1_, -rate));
}

// (G(u) W G(w)^T) z = r, G's rows the constraints' directions u and w (+ at a, - at b): a constraint couples only
// the constraints sharing a particle with it, a pattern that never changes (analysed once)
Eigen::VectorXd ConstraintSolver::solve(const Directions& u, const Directions& w, const Eigen::VectorXd& r) {
  if (m_ == 0) return r;  // no constraints: nothing to solve
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
  A_.setFromTriplets(entries.begin(), entries.end());
  if (!analysed_) lu_.analyzePattern(A_), analysed_ = true;
  lu_.factorize(A_);
  if (lu_.info() != Eigen::Success) return Eigen::VectorXd::Constant(m_, std::numeric_limits<double>::quiet_NaN());
  return lu_.solve(r);
}

// z += W G^T s, G's rows the directions n (positions or velocities)
void ConstraintSolver::move(double* z, const Directions& n, const Eigen::VectorXd& s) const {
  const int d = c_.dimension;
  for (Eigen::Index j = 0; j < m_; ++j) {
    const DistanceConstraint& c = c_.constraints[static_cast<size_t>(j)];
    for (int k = 0; k < d; ++k) {
      z[c.a * d + k] += c_.inverse_mass[static_cast<size_t>(c.a)] * s[j] * n(j, k);
      if (c.b >= 0) z[c.b * d + k] -= c_.inverse_mass[static_cast<size_t>(c.b)] * s[j] * n(j, k);
    }
  }
}

// |z_a|inf + |z_b|inf (twice the larger): the scale a constraint's rounding goes with
double ConstraintSolver::magnitude(const DistanceConstraint& c, const double* z) const {
  double m = 0;
  for (int k = 0; k < c_.dimension; ++k) {
    m = std::max(m, std::abs(z[c.a * c_.dimension + k]));
    if (c.b >= 0) m = std::max(m, std::abs(z[c.b * c_.dimension + k]));
  }
  return 2 * m;
}

}  // namespace stepwise
