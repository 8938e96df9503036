// The height field's method of lines (models/height_field.cpp's f: dz/dt = v, dv/dt = c^2 Lap z - mu v on
// the interior, the boundary still) on the grid split among the MPI ranks (distributed_wave.hpp), integrated
// by CVODE (`cvode-adams`: Adams with fixed-point iteration; `cvode-bdf`: BDF with Newton) or ARKODE (any
// `arkode-*` method: ERK, DIRK, or IMEX on the model's split, the Laplacian and z' = v implicit, the damping
// explicit) on SUNDIALS' parallel vector, set up as the table's adapters set them up: each rank's
// N_Vector_Parallel holds its block's z and v, f exchanges z's halo and computes each cell by the same kernel as
// one process (kernels/wave_acceleration.hpp), and the norms and dot products are sums over the ranks
// (MPI_Allreduce inside the vector). Newton's linear systems are solved by GMRES (SPGMR, matrix-free, J v by
// difference quotients) where one process uses KLU on the sparse Jacobian. The sums add in another order than
// one process's, so the step sizes the integrator picks differ in their last bits and the solutions by the
// tolerance's order, not by bits. SUNDIALS' and MPI's types stay in distributed_lines.cpp.
#pragma once

#include <stepwise/solvers/capabilities/wave_grid.hpp>
#include <stepwise/solvers/method.hpp>

#include <Eigen/Core>

#include <string>
#include <string_view>
#include <vector>

namespace stepwise {

struct DistributedLinesRun {
  std::vector<double> y;  // (z, v) of the whole grid at t_end, on rank 0 (empty on the others)
  long steps = 0, rhs_evals = 0;
  std::string failure;    // the failing SUNDIALS call and its code, or a method not run this way; empty when it reached t_end
};

// `method` (one whose on_ranks says CVODE or ARKODE: cvode-adams, cvode-bdf, the arkode-* methods) from y0 = (z, v)
// of the whole grid (every rank passes it; each takes its block) to t_end
DistributedLinesRun lines_distributed(const Method& method, const WaveGridView& grid, const Eigen::VectorXd& y0, double t_end, double rtol,
                                      double atol);

}  // namespace stepwise
