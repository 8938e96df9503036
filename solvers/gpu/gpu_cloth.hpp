// The explicit mass-spring cloth on the GPU: every node of a ClothGridView in one texel of two
// RGBA32F planes of the grid's size (plane 0: position, w = 1 where pinned; plane 1: velocity), stepped by
// a full-screen fragment pass into the other pair of planes (two colour attachments), then the pairs swap.
// A pass is one symplectic Euler step of solvers/cloth_grid.hpp, node by node: the twelve springs, the wind
// on the node's six triangles, the pick force, drag and gravity, then the sphere and the ground; in
// float32, those operations in that order and marked `precise`, so a conforming GPU gives the float32 CPU
// reference's bits (cloth_grid::step<float>; verification/gpu_references.hpp).
//
// The step is a pure gather (each node reads its neighbours' last state and writes only its own): a fragment
// pass over a render target expresses it with the seeds' ping-pong, and the state stays in textures a
// renderer's vertex shader can read; the compute pass (gpu-cloth-compute) runs the same node function over
// storage buffers, one invocation a node, on every unit of a GPU that gives fragment passes only a few. (A
// scatter, each spring once with its force added to both ends, would need atomics on floats, not in GL 4.5.)
#pragma once

#include <stepwise/solvers/gpu/gpu_grid.hpp>
#include <stepwise/solvers/cloth_grid.hpp>

namespace stepwise::gpu {

class GpuCloth final : public GpuGrid {
 public:
  GpuCloth(const Context& context, const ClothGridView& view, Pass pass = Pass::fragment);
  // the step's numbers (the wind at its start, h)
  void set_constants(const cloth_grid::Constants<float>& k);
  void upload(const cloth_grid::State<float>& s);
  void download(cloth_grid::State<float>& s) const;

 private:
  std::vector<float> pinned_;  // 1 for a pinned node, 0 for a free one, grid order
};

// registers gpu-cloth (GpuCloth stepping a cloth scene, one pass a step, read back for the run's state) and its
// compute twin gpu-cloth-compute with the solvers' method table
void register_cloth_methods(MethodTable& table);

}  // namespace stepwise::gpu
