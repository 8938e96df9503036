// Central finite-difference Jacobian df/dy, the twin of every analytic Jacobian.
#pragma once

#include <stepwise/solvers/ode_system.hpp>

namespace stepwise {

// dfdy (n x n) by central differences: column j = (f(y + e_j d) - f(y - e_j d)) / 2d,
// d = eps^(1/3) max(1, |y_j|), which balances truncation O(d^2) against round-off O(eps/d). Costs 2n calls of f.
void fd_jacobian(const OdeSystem& system, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                 Eigen::Ref<Eigen::MatrixXd> dfdy);

// the system's own Jacobian where it has one, else fd_jacobian
void jacobian_or_fd(const OdeSystem& system, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                    Eigen::Ref<Eigen::MatrixXd> dfdy);

}  // namespace stepwise
