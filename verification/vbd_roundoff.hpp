// The scale of the round-off in vbd's answer (solvers/vertex_block_descent.hpp): the magnitudes of each node's gradient
// terms, whose rounding is where a sweep's fixed point lies off backward Euler's step (tolerances.hpp's
// vbd_float32_step and vbd_float64_step). Shared by the vbd tests and the GPU pass's.
#pragma once

#include <stepwise/solvers/incremental_potential.hpp>

namespace stepwise {

// |S|_2 over the nodes at x: S_i the sum of the magnitudes of node i's gradient terms (the inertia's m / h^2 |e_i|, D0's
// |D0_ij| |e_j| / h, |f0_i|, and each spring's c (|L - l| + |r| + |x_i| + |x_j|): its length formed from the positions)
double gradient_scale(const IncrementalPotential& G, const MassSpringView& view, const Eigen::VectorXd& x);

}  // namespace stepwise
