// vbd's coloured sweeps as an OpenGL 4.3 compute pass (gpu-vbd-compute), on a mass-spring system whose elastic forces
// are its springs alone (a spring cloth, the hanging chain, the compliant pendulum): the step's host part is vbd's own
// (VbdStepper: the incremental potential's xb, f0 and D0 in float64, the start), and each sweep is a
// dispatch a colour over storage buffers, a barrier between colours, one invocation a node. An invocation does what
// vbd's CPU sweep does for its node (solvers/vertex_block_descent.cpp): the node's view of G (its springs, each
// spring's Hessian made semidefinite as Choi & Ko's clamp does; the rows of D0 at the node), the 3 x 3 Newton step
// by Cholesky, halved until the node's change of G meets Armijo's fraction of what the step predicts. That change is
// written as a difference (the inertia's e.d + d.d / 2, a spring's (L' - L)(L' + L - 2 l) with L' - L from the squared
// lengths' difference), as IncrementalPotential::change writes it: G's own terms, rounded to float32, would hide the
// decrease of the last sweeps. The state on the device is each node's displacement from the inertial point xb, so
// the step's positions, xb + e, carry float32's round-off of the displacement, not of the position.
//
// In float32 its answer is not vbd's bits: it converges to backward Euler's step to the float32 round-off of the
// node's gradient, scaled by the node's compliance h^2 / m (verification/tolerances.hpp's vbd_float32_step), and it
// stays out of the report's sweeps (its twin field: vbd) and the advice (the gpu family).
#pragma once

#include <stepwise/solvers/gpu/gpu_grid.hpp>
#include <stepwise/solvers/incremental_potential.hpp>

#include <Eigen/Dense>

#include <vector>

namespace stepwise::gpu {

class GpuVbd {
 public:
  // the network's springs by node and the colours' node lists uploaded once, and D0's pattern (`damping`, a step's D0)
  // read; GlError where the context has no compute shaders or a buffer would pass GL_MAX_SHADER_STORAGE_BLOCK_SIZE
  GpuVbd(const Context& context, const MassSpringView& network, const std::vector<std::vector<int>>& colours, const Eigen::SparseMatrix<double>& damping);
  ~GpuVbd();
  GpuVbd(const GpuVbd&) = delete;
  GpuVbd& operator=(const GpuVbd&) = delete;
  // a step's potential (xb, f0, D0's blocks at each node, h) and the sweeps' start x, uploaded
  void start(const IncrementalPotential& potential, const Eigen::VectorXd& x);
  // `count` sweeps over the colours, a dispatch a colour; GL errors thrown as GlError
  void sweep(int count);
  // x = xb + the displacements swept
  void download(const IncrementalPotential& potential, Eigen::VectorXd& x) const;
  // glFinish: the sweeps issued are done (for timing)
  void finish() const;

 private:
  // the blocks of D0 (3 x 3, padded in the plane) that a node's rows hold, in the order of its neighbour list
  void fill_damping_blocks(const Eigen::SparseMatrix<double>& d0);

  const Context& context_;
  const Gl& gl_;
  int nodes_, dimension_;
  std::vector<std::vector<int>> colours_;
  std::vector<int> colour_first_;               // each colour's first entry in the order buffer
  std::vector<int> block_first_;                // node i's D0 blocks are entries block_first_[i] .. block_first_[i + 1]
  std::vector<int> block_node_;                 // each entry's column node j
  std::vector<float> blocks_, xb_, f0_, e_;     // the per-step uploads
  unsigned buffers_[7] = {0, 0, 0, 0, 0, 0, 0};  // e, xb, f0, ranges, springs, blocks, order
  unsigned program_ = 0;
  int first_at_ = -1, count_at_ = -1, h_at_ = -1;  // the uniforms' locations
};

// "" or why `system` cannot be swept by gpu-vbd-compute on the GPU methods' device: no spring network, no compute
// shaders, or a buffer past the largest storage block
std::string vbd_device_problem(const OdeSystem& system);

// registers gpu-vbd-compute with the solvers' method table
void register_vbd_compute_method(MethodTable& table);

}  // namespace stepwise::gpu
