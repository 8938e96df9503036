// The explicit mass-spring cloth on the GPU (issue 9): every node of a ClothGridView in one texel of two
// RGBA32F planes of the grid's size (plane 0: position, w = 1 where pinned; plane 1: velocity), stepped by
// a full-screen fragment pass into the other pair of planes (two colour attachments), then the pairs swap.
// A pass is one symplectic Euler step of solvers/cloth_grid.hpp, node by node: the twelve springs, the wind
// on the node's six triangles, the pick force, drag and gravity, then the sphere and the ground; in
// float32, those operations in that order and marked `precise`, so a conforming GPU gives the float32 CPU
// reference's bits (cloth_grid::step<float>; verification/gpu_references.hpp).
//
// A fragment pass rather than a compute shader: the step is a pure gather (each node reads its neighbours'
// last state and writes only its own), which is exactly what a fragment pass over a render target
// expresses, with the seeds' ping-pong and no image stores, barriers or work-group sizes to choose; it
// shares GpuGrid with the water's passes, and the state stays in textures a renderer's vertex shader can
// read. A compute shader would pay off only for a scatter (each spring once, its force added to both ends),
// which needs atomics on floats that GL 4.5 does not have.
#pragma once

#include "gpu_grid.hpp"
#include "solvers/cloth_grid.hpp"

namespace stepwise::gpu {

class GpuCloth final : public GpuGrid {
 public:
  GpuCloth(const Context& context, const ClothGridView& view);
  // the step's numbers (the wind at its start, h)
  void set_constants(const cloth_grid::Constants<float>& k);
  void upload(const cloth_grid::State<float>& s);
  void download(cloth_grid::State<float>& s) const;

 private:
  std::vector<float> pinned_;  // 1 for a pinned node, 0 for a free one, grid order
};

// registers gpu-cloth (GpuCloth stepping a cloth scene, one pass a step, read back for the run's state) with
// the solvers' method table
void register_cloth_methods(MethodTable& table);

}  // namespace stepwise::gpu
