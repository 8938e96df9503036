#include "static_equilibrium.hpp"

#include "capabilities/mass_spring.hpp"
#include "capabilities/second_order.hpp"
#include "sparse_cholesky.hpp"

#include <Eigen/SparseCore>
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace stepwise {

StaticEquilibrium static_equilibrium(const OdeSystem& system, Eigen::VectorXd y, const std::vector<bool>& held, double tolerance, double stall,
                                     int max_iterations) {
  const auto* view = system.as<MassSpringView>();
  const auto* second = system.as<SecondOrderView>();
  if (!view || !second) throw std::invalid_argument("static_equilibrium: the system is no mass-spring or continuum system");
  const Eigen::Index n = 3 * Eigen::Index{view->nodes};
  if (y.size() != 2 * n || static_cast<Eigen::Index>(held.size()) != n) throw std::invalid_argument("static_equilibrium: sizes differ");
  y.tail(n).setZero();

  // the free coordinates, and the selection S (free x all) that takes K to K_ff = S K S^T
  std::vector<Eigen::Index> free;
  for (Eigen::Index i = 0; i < n; ++i)
    if (!held[static_cast<size_t>(i)]) free.push_back(i);
  const auto nf = static_cast<Eigen::Index>(free.size());
  Eigen::SparseMatrix<double> S(nf, n);
  std::vector<Eigen::Triplet<double>> ones;
  for (Eigen::Index k = 0; k < nf; ++k) ones.emplace_back(k, free[static_cast<size_t>(k)], 1.0);
  S.setFromTriplets(ones.begin(), ones.end());

  // f = M a at velocities zero
  const auto force = [&](const Eigen::VectorXd& at) {
    Eigen::VectorXd a(n);
    second->acceleration(0, at, a);
    for (int i = 0; i < view->nodes; ++i) a.segment<3>(3 * i) *= view->mass[static_cast<size_t>(i)];
    return a;
  };
  const auto free_part = [&](const Eigen::VectorXd& f) { return Eigen::VectorXd(S * f); };

  StaticEquilibrium out;
  Eigen::VectorXd f = force(y);
  Eigen::VectorXd reactions = f;
  for (const Eigen::Index i : free) reactions[i] = 0;
  out.scale = std::max(f.norm(), 1e-300);
  double norm = free_part(f).norm();
  SparseCholesky factor;
  Eigen::SparseMatrix<double> K, D;
  Eigen::MatrixXd rhs, dx;
  for (; out.iterations < max_iterations; ++out.iterations) {
    out.scale = std::max({out.scale, reactions.norm()});
    out.residuals.push_back(norm / out.scale);
    if (norm <= tolerance * out.scale) break;
    view->force_jacobians(0, y, true, K, D);
    const Eigen::SparseMatrix<double> A = -(S * K * S.transpose());
    if (out.iterations == 0)
      if (auto e = factor.analyze(A, Ordering::amd); !e.empty()) {
        out.failure = fmt::format("static_equilibrium: {}", e);
        break;
      }
    if (auto e = factor.factorize(A); !e.empty()) {
      out.failure = fmt::format("static_equilibrium: {} at iteration {}", e, out.iterations);
      break;
    }
    rhs = free_part(f);
    if (auto e = factor.solve(rhs, dx); !e.empty()) {
      out.failure = fmt::format("static_equilibrium: {} at iteration {}", e, out.iterations);
      break;
    }
    // backtracking: the full step, halved until the residual falls (Armijo's sufficient decrease, 1e-4)
    double alpha = 1;
    Eigen::VectorXd trial = y, f_trial;
    double trial_norm = 0;
    for (;; alpha /= 2) {
      trial = y;
      for (Eigen::Index k = 0; k < nf; ++k) trial[free[static_cast<size_t>(k)]] += alpha * dx(k, 0);
      f_trial = force(trial);
      trial_norm = free_part(f_trial).norm();
      if (trial_norm <= (1 - 1e-4 * alpha) * norm || alpha < 1e-6) break;
    }
    if (!(trial_norm < norm)) {
      // no step lowers |f|: the round-off of the forces' sum is reached. Within `stall` of the scale that is
      // the equilibrium as far as the forces can say; above it, a failure
      if (norm > stall * out.scale)
        out.failure = fmt::format("static_equilibrium: the line search found no decrease of |f| = {:.3g} at iteration {}", norm, out.iterations);
      break;
    }
    y = std::move(trial);
    f = std::move(f_trial);
    norm = trial_norm;
    reactions = f;
    for (const Eigen::Index i : free) reactions[i] = 0;
  }
  if (out.failure.empty() && norm > std::max(tolerance, stall) * out.scale)
    out.failure = fmt::format("static_equilibrium: |f| = {:.3g} of {:.3g} after {} iterations", norm, out.scale, out.iterations);
  out.residual = norm / out.scale;
  out.y = std::move(y);
  return out;
}

}  // namespace stepwise
