// Springs of a mass-spring system (seeds: Hooke's law with Voigt damping): between nodes a and b, with
// r = x_b - x_a, L = |r|, u = r / L, elongation e = L - l and its rate de/dt = u . (v_b - v_a), the force
//   F = (c e + gamma de/dt) u  on a,  -F on b.
// Its exact derivatives, for a Jacobian (w = v_b - v_a):
//   dF/dr = c u u^T + (c e + gamma de/dt) / L (1 - u u^T) + gamma / L u w^T (1 - u u^T),   dF/dw = gamma u u^T,
// with dF/dx_a = -dF/dr, dF/dx_b = dF/dr (and the same for v). A compressed spring (e < 0) makes the middle
// term indefinite; these are the exact derivatives, which CVODE's Newton iteration wants (a symmetric
// definite approximation for a Cholesky solve is the cloth's business).
// A spring may hang from a fixed anchor instead of a node (a = -1): a pin.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <span>
#include <vector>

namespace stepwise {

struct Spring {
  int a = -1, b = 0;                                 // node indices; a = -1: the fixed point `anchor`
  double rest = 1;                                   // l (m)
  double stiffness = 0;                              // c (N/m)
  double damping = 0;                                // gamma (N s/m)
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();  // where a pinned spring hangs from (m)
};

// f[3i..3i+3) += the springs' forces on node i; x, v, f hold 3 entries per node
void add_spring_forces(std::span<const Spring> springs, const double* x, const double* v, double* f);

// the springs' potential energy, sum c e^2 / 2
double spring_energy(std::span<const Spring> springs, const double* x);

// triplets of scale * dF/dx at (row0 + 3i, x0 + 3j) and scale * dF/dv at (row0 + 3i, v0 + 3j), node forces
// by node positions and velocities: the acceleration rows of y' = (v, f / m) with scale = 1 / m
void add_spring_jacobian(std::span<const Spring> springs, const double* x, const double* v, double scale, Eigen::Index row0,
                         Eigen::Index x0, Eigen::Index v0, std::vector<Eigen::Triplet<double>>& out);

}  // namespace stepwise
