// The seeds' wave scheme on the GPU (issue 9): the height field's two time levels in one RGBA32F texture
// of the grid's size (R = z^k, G = z^{k-1}), stepped by a full-screen fragment pass that reads texture A
// and writes texture B, then the two swap (ping-pong). A pass computes
//
//   z^{k+1} = self z^k + previous z^{k-1} + neighbours ((z_down + z_up) + (z_left + z_right))
//
// in float32, the operations of solvers/wave_step.hpp's wave_cell in the same order and marked `precise`
// (no fused multiply-adds, no reassociation), so a conforming GPU gives the bits of the float32 CPU loop
// (verification/wave_modes.hpp); the boundary holds its values, as on the CPU. The texture can be drawn
// from directly (its R channel is the surface), so nothing goes back to the CPU between steps.
#pragma once

#include "context.hpp"
#include "solvers/wave_step.hpp"

#include <Eigen/Dense>

namespace stepwise::render {

class GpuWave {
 public:
  // a points^2 grid on `context` (made current); GlError naming the limit where points passes
  // GL_MAX_TEXTURE_SIZE, or where the context cannot render to RGBA32F
  GpuWave(const Context& context, int points, const BasicWaveCoefficients<float>& k);
  ~GpuWave();
  GpuWave(const GpuWave&) = delete;
  GpuWave& operator=(const GpuWave&) = delete;

  // both levels, each points^2 row-major (the CPU grids' layout)
  void upload(const Eigen::VectorXf& z_prev, const Eigen::VectorXf& z);
  // the coefficients of another step size
  void set_coefficients(const BasicWaveCoefficients<float>& k);
  // `count` passes; GL errors thrown as GlError
  void step(long count);
  // glFinish: the passes issued are done (for timing)
  void finish() const;
  void download(Eigen::VectorXf& z_prev, Eigen::VectorXf& z) const;
  GLuint texture() const { return textures_[current_]; }

 private:
  const Context& context_;
  const Gl& gl_;
  int points_;
  GLuint textures_[2] = {0, 0}, framebuffers_[2] = {0, 0};
  GLuint program_ = 0, vertex_array_ = 0;
  int current_ = 0;  // the texture holding the state
};

// registers the GPU shader methods (gpu-wave: GpuWave stepping a wave scene, wave_fd.hpp's start and
// velocities around it) with the solvers' method table. Each run makes its own context, OSMesa unless
// STEPWISE_GPU_BACKEND=egl
void register_gpu_methods();

}  // namespace stepwise::render
