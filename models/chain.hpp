// An inextensible chain of N rigid links (the second constrained scene): N point masses in the plane, each
// held at the link length l = L / N from the one before it, the first from a pin at the origin; released from
// rest along the horizontal, gravity along -y. State y = (x_1, y_1, ..., x_N, y_N, then the velocities).
// Parameters: links N, length L (the chain's), mass (the chain's, m / N a link), g.
//
// Its f, for the ODE methods, holds the constraints g_j = (|d_j|^2 - l^2) / 2 = 0 (d_j = x_j - x_{j-1}) at
// their second derivative: the multipliers solve the tridiagonal system (G W G^T) lambda = -(|d_j'|^2 +
// d_j . (a_j - a_{j-1})) (W the inverse masses, a the gravity alone), by Eigen's sparse LDL^T, and
// a_i = g + w_i (lambda_i d_i - lambda_{i+1} d_{i+1}). The position-based and constrained methods step it
// through the DistanceConstraints capability. No exact solution: its reference is a converged run
// (verification/tests/test_constraints.cpp: RATTLE and verner98 on the ODE agree).
#pragma once

#include <stepwise/models/model.hpp>

namespace stepwise {

std::span<const ParamSpec> chain_params();

std::unique_ptr<Model> make_chain(const Params& params);

// trajectory.csv's columns for these parameters (the output budget, before the model is made)
double chain_columns(const Params& params);

}  // namespace stepwise
