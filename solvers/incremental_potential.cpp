#include "incremental_potential.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace stepwise {

namespace {

constexpr double armijo = 1e-4;   // the fraction of the predicted decrease of G a step must deliver
constexpr int max_halvings = 30;  // the shortest step tried: 2^-30 of Newton's
// the mass term's raise tried on an indefinite Hessian: from 1/64 of M up to 64 M (then the projected Hessian)
constexpr double min_shift = 1.0 / 64, max_shift = 64;
// G's round-off: a few dozen ulps of it, the sum of its terms' (inertia, the forces' work, the elements' energies)
constexpr double round_off_decrease = 64 * std::numeric_limits<double>::epsilon();
// CG's direction is refined until the correction left moves no node by more than this fraction of what the velocity
// tolerance allows a step (the correction as the factor predicts it, when the factor is of the exact Hessian at an
// earlier iterate of the step: of a raised or semidefinite one, it underestimates the correction along the modes it
// stiffens)
constexpr double refinement = 0.01;

}  // namespace

void StepMatrix::operator()(const Eigen::VectorXd& mass, const Eigen::SparseMatrix<double>& d, const Eigen::SparseMatrix<double>& k, double h,
                            Eigen::SparseMatrix<double>& a) {
  const auto same_sizes = [&]() {
    return d.isCompressed() && k.isCompressed() && a.isCompressed() && d.rows() == k.rows() && d.cols() == k.cols() && a.rows() == k.rows() &&
           a.cols() == k.cols() && d.nonZeros() == k.nonZeros() && a.nonZeros() == k.nonZeros();
  };
  if (!shared_ || !same_sizes()) {
    const auto same_pattern = [](const Eigen::SparseMatrix<double>& p, const Eigen::SparseMatrix<double>& q) {
      return p.isCompressed() && q.isCompressed() && p.rows() == q.rows() && p.cols() == q.cols() && p.nonZeros() == q.nonZeros() &&
             std::equal(p.outerIndexPtr(), p.outerIndexPtr() + p.cols() + 1, q.outerIndexPtr()) &&
             std::equal(p.innerIndexPtr(), p.innerIndexPtr() + p.nonZeros(), q.innerIndexPtr());
    };
    shared_ = same_pattern(d, k);
    diagonal_.assign(static_cast<size_t>(k.cols()), -1);
    for (Eigen::Index c = 0; shared_ && c < k.cols(); ++c) {
      for (Eigen::Index at = k.outerIndexPtr()[c]; at < k.outerIndexPtr()[c + 1]; ++at)
        if (k.innerIndexPtr()[at] == c) diagonal_[static_cast<size_t>(c)] = at;
      shared_ = diagonal_[static_cast<size_t>(c)] >= 0;
    }
    if (!shared_) {
      Eigen::SparseMatrix<double> m(mass.size(), mass.size());
      m.setIdentity();
      m.diagonal() = mass;
      a = m - h * d - (h * h) * k;
      a.makeCompressed();
      return;
    }
    if (!same_pattern(a, k)) a = k;
  }
  const double* dv = d.valuePtr();
  const double* kv = k.valuePtr();
  double* av = a.valuePtr();
  for (Eigen::Index at = 0; at < k.nonZeros(); ++at) av[at] = -h * dv[at] - (h * h) * kv[at];
  for (Eigen::Index c = 0; c < k.cols(); ++c) {
    const Eigen::Index at = diagonal_[static_cast<size_t>(c)];
    av[at] = (mass[c] - h * dv[at]) - (h * h) * kv[at];
  }
}

IncrementalPotential::IncrementalPotential(const CountedSystem& system, const MassSpringView& view)
    : system_(system), view_(view), m_(coordinate_masses(view)) {}

void IncrementalPotential::start(double t0, const Eigen::VectorXd& y0, double h) {
  Eigen::VectorXd force(m_.size());
  second_order_acceleration(system_, *system_.as<SecondOrderView>(), t0, y0, force, scratch_);
  force = force.cwiseProduct(m_);
  force_jacobians(system_, view_, t0, y0, true, k_, d0_);
  start(t0, y0, h, force, d0_);
}

void IncrementalPotential::start(double t0, const Eigen::VectorXd& y0, double h, const Eigen::VectorXd& force,
                                 const Eigen::SparseMatrix<double>& damping) {
  const Eigen::Index n = m_.size();
  t0_ = t0;
  h_ = h;
  x0_ = y0.head(n);
  xb_ = x0_ + h * y0.tail(n);
  if (&damping != &d0_) d0_ = damping;
  // f0 = f(t0, y0) - f_e(x0): the whole force (M a) less the elastic one
  f0_ = force;
  Eigen::VectorXd elastic = Eigen::VectorXd::Zero(n);
  view_.elastic_force(x0_, elastic);
  f0_ -= elastic;
}

double IncrementalPotential::value(const Eigen::VectorXd& x) const {
  const Eigen::VectorXd d = x - xb_;
  const double inertia = d.cwiseAbs2().dot(m_) / (2 * h_ * h_) - d.dot(d0_ * d) / (2 * h_);
  return inertia - f0_.dot(x) + view_.potential(x);
}

double IncrementalPotential::change(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const {
  double after = 0;
  return change(x, dx, elastic(x), after);
}

double IncrementalPotential::change(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double elastic_at_x, double& elastic_after) const {
  const Eigen::VectorXd d = x - xb_;
  // 1/2 (d + dx)^T A (d + dx) - 1/2 d^T A d = dx^T A d + 1/2 dx^T A dx, A = M / h^2 - D0 / h (symmetric)
  const Eigen::VectorXd a_dx = dx.cwiseProduct(m_) / (h_ * h_) - (d0_ * dx) / h_;
  elastic_after = elastic(x + dx);
  return a_dx.dot(d) + a_dx.dot(dx) / 2 - f0_.dot(dx) + (elastic_after - elastic_at_x);
}

double IncrementalPotential::elastic(const Eigen::VectorXd& x) const { return view_.potential(x); }

void IncrementalPotential::gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const {
  const Eigen::VectorXd d = x - xb_;
  g = d.cwiseProduct(m_) / (h_ * h_) - (d0_ * d) / h_ - f0_;
  // - f_e(x): the elastic force subtracted in place
  scratch_ = Eigen::VectorXd::Zero(x.size());
  view_.elastic_force(x, scratch_);
  g -= scratch_;
}

void IncrementalPotential::scaled_hessian(const Eigen::VectorXd& x, bool definite, Eigen::SparseMatrix<double>& a) const {
  view_.elastic_jacobian(x, definite, k_);
  step_matrix_(m_, d0_, k_, h_, a);
}

IncrementalPotential::Vertex IncrementalPotential::vertex(int i, const Eigen::VectorXd& x, bool definite, bool derivatives) const {
  // node i's coordinates as 3-vectors (in the plane, z zero: no gradient along it, the mass term its curvature)
  const int dim = view_.dimension;
  const Eigen::Index at = dim * Eigen::Index{i};
  Eigen::Vector3d e = Eigen::Vector3d::Zero(), xi = Eigen::Vector3d::Zero(), f0i = Eigen::Vector3d::Zero();
  e.head(dim) = x.segment(at, dim) - xb_.segment(at, dim);
  xi.head(dim) = x.segment(at, dim);
  f0i.head(dim) = f0_.segment(at, dim);
  // (D0 (x - xb))_i and D0's block (i, i), from D0's columns at node i (it is symmetric)
  Eigen::Vector3d d0e = Eigen::Vector3d::Zero();
  Eigen::Matrix3d d0ii = Eigen::Matrix3d::Zero();
  for (int c = 0; c < dim; ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(d0_, at + c); it; ++it) {
      d0e[c] += it.value() * (x[it.row()] - xb_[it.row()]);
      if (it.row() >= at && it.row() < at + dim) d0ii(it.row() - at, c) = it.value();
    }
  VertexElastic elastic;
  view_.vertex_elastic(i, x, definite, derivatives, elastic);
  const double m = m_[at], hh = h_ * h_;
  // 1/2 d^T (M / h^2 - D0 / h) d's terms in e, the others' work, and node i's elastic terms
  Vertex out;
  out.elastic_energy = elastic.energy;
  out.value = m * e.squaredNorm() / (2 * hh) - (e.dot(d0e) - e.dot(d0ii * e) / 2) / h_ - f0i.dot(xi) + elastic.energy;
  if (!derivatives) return out;
  out.quadratic_gradient = m * e / hh - d0e / h_ - f0i;
  out.quadratic_hessian = m / hh * Eigen::Matrix3d::Identity() - d0ii / h_;
  out.gradient = out.quadratic_gradient;
  out.gradient.head(dim) -= elastic.force.head(dim);
  out.hessian = out.quadratic_hessian;
  out.hessian.topLeftCorner(dim, dim) -= elastic.jacobian.topLeftCorner(dim, dim);
  return out;
}

double IncrementalPotential::vertex_change(int i, const Eigen::VectorXd& x, const Vertex& at, const Eigen::Vector3d& d) const {
  VertexElastic elastic;
  view_.vertex_elastic(i, x, true, false, elastic);
  return at.quadratic_gradient.dot(d) + d.dot(at.quadratic_hessian * d) / 2 + (elastic.energy - at.elastic_energy);
}

std::string PotentialNewton::factor_positive_definite(const IncrementalPotential& potential, const Eigen::VectorXd& x, Stats& stats) {
  ++stats.factorizations;
  factored_exact_ = factor_.factorize(a_).empty();
  if (factored_exact_) return "";
  // not positive definite here: the exact Hessian with its mass term raised, A + tau M (Nocedal & Wright's Hessian
  // modification, in the mass's metric), tau from a quarter of the last one that served (kept through the exact
  // factors between, as IPOPT keeps its last regularisation: the sheet buckles again much as it did; measured against
  // starting from the smallest each time: docs/performance-cloth.md), raised fourfold until the factor exists; past
  // that, the semidefinite elements' Hessian
  const Eigen::SparseMatrix<double> exact = a_;
  for (shift_ = std::max(shift_ / 4, min_shift); shift_ <= max_shift; shift_ *= 4) {
    a_ = exact;
    a_.diagonal() += shift_ * potential.mass();
    ++stats.factorizations;
    if (factor_.factorize(a_).empty()) return "";
  }
  shift_ = max_shift;
  potential.scaled_hessian(x, true, a_);
  ++stats.factorizations;
  return factor_.factorize(a_);
}

bool PotentialNewton::preconditioned_direction(double forcing, double enough, Stats& stats) {
  // Newton-CG (Nocedal & Wright, Algorithm 7.1, preconditioned): CG on a_ dx = b from dx = 0, stopped where
  // |b - a_ dx| <= forcing |b|, or where a direction p has p^T a_ p <= 0 (a_ indefinite there: the iterate so far is
  // returned, a descent direction of G; at the first, the preconditioned residual P^-1 b, descent as P is definite).
  // Stopped too where the correction the factor predicts, z = P^-1 r, moves no node by more than `enough`: the
  // direction is then within that of a_^-1 b, and more iterations would refine what the stopping rule cannot see
  const auto precondition = [&](const Eigen::VectorXd& r) {
    ++stats.linear_solves;
    return factor_.solve(r, z_).empty() && z_.allFinite();
  };
  const Eigen::VectorXd& b = rhs_.col(0);
  r_ = b;
  if (!precondition(r_)) return false;
  p_ = z_.col(0);
  dx_.setZero(b.size(), 1);
  if (p_.lpNorm<Eigen::Infinity>() <= enough) {
    dx_.col(0) = p_;
    return true;
  }
  double rz = r_.dot(p_);
  const double start_residual = b.norm(), start_correction = p_.lpNorm<Eigen::Infinity>();
  const double target = forcing * start_residual;
  for (int j = 0; j < options_.max_cg_iterations; ++j) {
    // the first iterations' rate predicts the rest (preconditioned CG converges about geometrically here): where
    // neither the forcing term nor `enough` would be met within max_cg_iterations, the factor is given up after them,
    // not after all max_cg_iterations (measured: docs/performance-cloth.md, backward Euler's Newton)
    if (j > 0 && j == options_.cg_probe_iterations) {
      const double by_residual = predicted_iterations(start_residual, r_.norm(), j, target);
      const double by_correction = enough > 0 ? predicted_iterations(start_correction, z_.col(0).lpNorm<Eigen::Infinity>(), j, enough)
                                              : std::numeric_limits<double>::infinity();
      if (std::min(by_residual, by_correction) > options_.max_cg_iterations) return false;
    }
    ap_.noalias() = a_ * p_;
    const double curvature = p_.dot(ap_);
    if (!(curvature > 0)) {
      if (j == 0) dx_.col(0) = p_;
      return true;
    }
    const double alpha = rz / curvature;
    dx_.col(0) += alpha * p_;
    r_ -= alpha * ap_;
    if (r_.norm() <= target) return true;
    if (!precondition(r_)) return false;
    if (z_.col(0).lpNorm<Eigen::Infinity>() <= enough) return true;
    const double next = r_.dot(z_.col(0));
    p_ = z_.col(0) + (next / rz) * p_;
    rz = next;
  }
  return false;
}

std::string PotentialNewton::minimise(const IncrementalPotential& potential, Eigen::VectorXd& x, Stats& stats) {
  bool factored = false;  // the step's factor, of A at an earlier iterate, is there
  const double h = potential.h();
  double value = potential.value(x);
  double elastic = potential.elastic(x);  // Psi(x), carried along as x moves (the line search's trials need it)
  const double start_value = value;
  double moved = std::numeric_limits<double>::infinity(), last_gradient = 0;
  for (int iteration = 0; iteration < options_.max_iterations; ++iteration) {
    if (!std::isfinite(value)) return fmt::format("G is not finite at Newton iteration {}", iteration);
    // the direction: (M - h D0 - h^2 K) dx = -h^2 grad G
    potential.gradient(x, g_);
    potential.scaled_hessian(x, false, a_);
    if (!analysed_) {
      if (auto e = factor_.analyze(a_, options_.ordering); !e.empty()) return e;
      analysed_ = true;
    }
    rhs_ = -(h * h) * g_;
    // Eisenstat & Walker's forcing term (their choice 2: 0.9 |g_k|^2 / |g_k-1|^2), at most max_forcing
    const double gradient = g_.norm();
    const double forcing = iteration > 0 && last_gradient > 0 ? std::min(options_.max_forcing, 0.9 * std::pow(gradient / last_gradient, 2))
                                                               : options_.max_forcing;
    last_gradient = gradient;
    // the step's first direction from a fresh factor (the step has moved the matrix), the others by CG on it
    if (!factored || !options_.inexact || !preconditioned_direction(forcing, factored_exact_ ? refinement * options_.velocity_tolerance * h : 0.0, stats)) {
      if (auto e = factor_positive_definite(potential, x, stats); !e.empty()) return e;
      factored = true;
      if (auto e = factor_.solve(rhs_, dx_); !e.empty()) return e;
      ++stats.linear_solves;
    }
    ++stats.newton_iterations;
    moved = dx_.col(0).lpNorm<Eigen::Infinity>() / h;
    if (options_.observe) options_.observe(iteration, value, moved);
    // converged: Newton's step moves no node faster than the tolerance; it is taken (its error is the next one's).
    // (Not where Newton's contraction predicts the error after it below the tolerance, Hairer & Wanner's rule: on the
    // buckling flag a step 0.07 of the last, in a valley Newton then wanders along for 15 iterations, stopped 0.2 px
    // short of the minimiser)
    if (moved <= options_.velocity_tolerance) {
      x += dx_.col(0);
      return "";
    }
    // converged too where the decrease the step predicts is G's round-off: the gradient has vanished, and what is
    // left of the step lies along directions G barely sees (a sheet that barely bends, buckling: a soft mode whose
    // Newton step stays 1e-6 m/s long while G's slope along it is 1e-17 J, measured on the continuum flag)
    const double slope = g_.dot(dx_.col(0));
    if (-slope <= round_off_decrease * std::abs(value)) return "";
    // the line search on G itself
    bool lowered = false;
    for (int halving = 0; halving <= max_halvings && !lowered; ++halving) {
      const double alpha = std::ldexp(1.0, -halving);
      trial_ = alpha * dx_.col(0);
      double elastic_trial = 0;
      const double change = potential.change(x, trial_, elastic, elastic_trial);
      lowered = change <= armijo * alpha * slope;
      if (lowered) {
        x += trial_;
        value += change;
        elastic = elastic_trial;
      } else {
        ++stats.line_search_halvings;
      }
    }
    if (!lowered)
      return fmt::format("no step along Newton's direction lowered G at iteration {} (down to 2^-{} of it; G fell by {:.3g} J before, the step "
                         "moved a node at {:.3g} m/s)",
                         iteration, max_halvings, start_value - value, moved);
  }
  return fmt::format("did not converge in {} Newton iterations (G fell by {:.3g} J; the last step moved a node at {:.3g} m/s, the tolerance {:.1e})",
                     options_.max_iterations, start_value - value, moved, options_.velocity_tolerance);
}

}  // namespace stepwise
