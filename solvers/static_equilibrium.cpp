#include "static_equilibrium.hpp"

#include "capabilities/mass_spring.hpp"
#include "capabilities/second_order.hpp"
#include "sparse_cholesky.hpp"

#include <Eigen/SparseCore>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace stepwise {

namespace {

// the problem the iteration and its line search share: the system's views, and the free coordinates with the
// selection S (free x all) that takes K to K_ff = S K S^T
struct Problem {
  const MassSpringView& view;
  const SecondOrderView& second;
  Eigen::Index n;
  std::vector<Eigen::Index> free;
  Eigen::SparseMatrix<double> S;

  // f = M a at velocities zero
  Eigen::VectorXd force(const Eigen::VectorXd& at) const {
    Eigen::VectorXd a(n);
    second.acceleration(0, at, a);
    return a.cwiseProduct(coordinate_masses(view));
  }
  Eigen::VectorXd free_part(const Eigen::VectorXd& f) const { return S * f; }
};

// a step tried: accepted or not, the state, its force and the free force's norm there
struct Trial {
  bool accepted = false;
  Eigen::VectorXd y, f;
  double norm = 0;
};

// backtracking along Newton's step dx (free coordinates) from y, where the force is f and its free part's norm
// `norm`: the full step, halved until the energy or the residual falls by Armijo's fraction (1e-4) of what the step
// predicts. The energy, Pi(x) = Psi(x) - f_o . x with the other forces f_o = f - f_e taken where the iteration
// stands (exact for gravity), is what a stiff membrane needs: Newton from a flat plate bends it without the
// in-plane shortening that keeps its midplane unstretched, and the residual of that stretch, many times the load,
// rejects the steps that lower Pi. The residual takes over where Pi's round-off hides its decrease
Trial line_search(const Problem& p, const Eigen::VectorXd& y, const Eigen::VectorXd& f, double norm, const Eigen::VectorXd& dx) {
  const Eigen::Index n = p.n;
  bool energy = static_cast<bool>(p.view.potential);
  Eigen::VectorXd other;
  double pi = 0, slope = 0;  // Pi here, and its derivative along the step (-f_free . dx)
  if (energy) {
    other = f;
    Eigen::VectorXd elastic = Eigen::VectorXd::Zero(n);
    p.view.elastic_force(y.head(n), elastic);
    other -= elastic;
    const double psi = p.view.potential(y.head(n)), work = other.dot(y.head(n));
    pi = psi - work;
    slope = -p.free_part(f).dot(dx);
    // Pi's decrease is seen above its terms' round-off only
    energy = -slope > 1e3 * std::numeric_limits<double>::epsilon() * (std::abs(psi) + std::abs(work));
  }
  Trial trial;
  for (double alpha = 1; !trial.accepted && alpha >= 1e-6; alpha /= 2) {
    trial.y = y;
    for (size_t k = 0; k < p.free.size(); ++k) trial.y[p.free[k]] += alpha * dx[static_cast<Eigen::Index>(k)];
    trial.f = p.force(trial.y);
    trial.norm = p.free_part(trial.f).norm();
    trial.accepted = trial.norm <= (1 - 1e-4 * alpha) * norm ||
                     (energy && p.view.potential(trial.y.head(n)) - other.dot(trial.y.head(n)) <= pi + 1e-4 * alpha * slope);
  }
  return trial;
}

}  // namespace

StaticEquilibrium static_equilibrium(const OdeSystem& system, Eigen::VectorXd y, const std::vector<bool>& held, double tolerance, double stall,
                                     int max_iterations) {
  const auto* view = system.as<MassSpringView>();
  const auto* second = system.as<SecondOrderView>();
  if (!view || !second) throw std::invalid_argument("static_equilibrium: the system is no mass-spring or continuum system");
  const Eigen::Index n = Eigen::Index{view->dimension} * view->nodes;
  if (y.size() != 2 * n || static_cast<Eigen::Index>(held.size()) != n) throw std::invalid_argument("static_equilibrium: sizes differ");
  y.tail(n).setZero();

  Problem p{*view, *second, n, {}, {}};
  for (Eigen::Index i = 0; i < n; ++i)
    if (!held[static_cast<size_t>(i)]) p.free.push_back(i);
  const auto nf = static_cast<Eigen::Index>(p.free.size());
  p.S.resize(nf, n);
  std::vector<Eigen::Triplet<double>> ones;
  for (Eigen::Index k = 0; k < nf; ++k) ones.emplace_back(k, p.free[static_cast<size_t>(k)], 1.0);
  p.S.setFromTriplets(ones.begin(), ones.end());

  StaticEquilibrium out;
  Eigen::VectorXd f = p.force(y);
  Eigen::VectorXd reactions = f;
  for (const Eigen::Index i : p.free) reactions[i] = 0;
  out.scale = std::max(f.norm(), 1e-300);
  double norm = p.free_part(f).norm();
  bool stalled = false;  // judged at a stall: no failure after it
  SparseCholesky factor;
  Eigen::SparseMatrix<double> K, D;
  Eigen::MatrixXd rhs, dx;
  for (; out.iterations < max_iterations; ++out.iterations) {
    out.scale = std::max({out.scale, reactions.norm()});
    out.residuals.push_back(norm / out.scale);
    if (norm <= tolerance * out.scale) break;
    // the exact Hessian where it is positive definite (Newton's quadratic convergence), else the definite one
    std::string error;
    for (const bool definite : {false, true}) {
      view->force_jacobians(0, y, definite, K, D);
      const Eigen::SparseMatrix<double> A = -(p.S * K * p.S.transpose());
      if (out.iterations == 0 && !definite)
        if (error = factor.analyze(A, Ordering::amd); !error.empty()) break;
      if (error = factor.factorize(A); error.empty()) break;
    }
    if (!error.empty()) {
      out.failure = fmt::format("static_equilibrium: {} at iteration {}", error, out.iterations);
      break;
    }
    rhs = p.free_part(f);
    if (auto e = factor.solve(rhs, dx); !e.empty()) {
      out.failure = fmt::format("static_equilibrium: {} at iteration {}", e, out.iterations);
      break;
    }
    // Newton's step within `stall` of the positions: the equilibrium as far as they can say (a stiff membrane's internal
    // forces, many times the load, leave a residual whose round-off the load's scale does not see)
    if (dx.col(0).lpNorm<Eigen::Infinity>() <= stall * y.head(n).lpNorm<Eigen::Infinity>()) {
      stalled = true;
      break;
    }
    Trial trial = line_search(p, y, f, norm, dx.col(0));
    if (!trial.accepted) {
      // no step lowers |f| or Pi: the round-off of the forces' sum is reached. Within `stall` of the scale that is the
      // equilibrium as far as the forces can say; above it, a failure
      if (norm > stall * out.scale)
        out.failure = fmt::format("static_equilibrium: the line search found no decrease of |f| = {:.3g} at iteration {}", norm, out.iterations);
      stalled = true;
      break;
    }
    y = std::move(trial.y);
    f = std::move(trial.f);
    norm = trial.norm;
    reactions = f;
    for (const Eigen::Index i : p.free) reactions[i] = 0;
  }
  if (out.failure.empty() && norm > std::max(tolerance, stall) * out.scale && !stalled)
    out.failure = fmt::format("static_equilibrium: |f| = {:.3g} of {:.3g} after {} iterations", norm, out.scale, out.iterations);
  out.residual = norm / out.scale;
  out.y = std::move(y);
  return out;
}

}  // namespace stepwise
