// The seeds' wave schemes on the GPU (issue 9), as solvers: they step model state, so they live here and
// not in render/, which only lends them its GL context. The three-level scheme keeps the height field's
// two time levels in one RGBA32F texture of the grid's size (R = z^k, G = z^{k-1}), stepped by a
// full-screen fragment pass that reads texture A and writes texture B, then the two swap (ping-pong). A
// pass computes
//
//   z^{k+1} = self z^k + previous z^{k-1} + neighbours ((z_down + z_up) + (z_left + z_right))
//
// in float32, the operations of solvers/wave_step.hpp's wave_cell in the same order and marked `precise`
// (no fused multiply-adds, no reassociation), so a conforming GPU gives the bits of the float32 CPU loop
// (verification/wave_modes.hpp); the boundary holds its values, as on the CPU. Between steps that follow
// one another the state stays on the device; the methods read each new level back for the run's samples.
#pragma once

#include "render/context.hpp"
#include "solvers/wave_step.hpp"

#include <Eigen/Dense>

#include <string>

namespace stepwise::gpu {

using render::Context;
using render::Gl;

// a grid's state in the red and green channels of two RGBA32F textures of its size, stepped by a full-screen
// fragment pass from one into the other, ping-pong; texel (x, y) is cell y * points + x. `pass`: the
// subclass's GLSL main and uniforms, after the shared part (gpu_wave.cpp's grid_pass)
class GpuGrid {
 public:
  // GlError naming the limit where points passes GL_MAX_TEXTURE_SIZE, or where the context cannot render to
  // RGBA32F
  GpuGrid(const Context& context, int points, const char* pass, const std::string& name);
  virtual ~GpuGrid();
  GpuGrid(const GpuGrid&) = delete;
  GpuGrid& operator=(const GpuGrid&) = delete;
  // `count` passes; GL errors thrown as GlError
  void step(long count);
  // glFinish: the passes issued are done (for timing)
  void finish() const;

 protected:
  // the two channels, points^2 each, row-major (the CPU grids' layout)
  void upload_channels(const Eigen::VectorXf& red, const Eigen::VectorXf& green);
  void download_channels(Eigen::VectorXf& red, Eigen::VectorXf& green) const;
  void uniform(const char* name, float value) const;

 private:
  const Context& context_;
  const Gl& gl_;
  int points_;
  unsigned textures_[2] = {0, 0}, framebuffers_[2] = {0, 0};
  unsigned program_ = 0, vertex_array_ = 0;
  int current_ = 0;  // the texture holding the state
};

// the seeds' three-level scheme: R = z^k, G = z^{k-1}
class GpuWave final : public GpuGrid {
 public:
  GpuWave(const Context& context, int points, const BasicWaveCoefficients<float>& k);
  // the coefficients of another step size
  void set_coefficients(const BasicWaveCoefficients<float>& k);
  void upload(const Eigen::VectorXf& z_prev, const Eigen::VectorXf& z) { upload_channels(z, z_prev); }
  void download(Eigen::VectorXf& z_prev, Eigen::VectorXf& z) const { download_channels(z, z_prev); }
};

// the second seed's scheme, symplectic Euler with the damping explicit: v += (c^2 Lap z - mu v) dt, then
// z += v dt (models/height_field.hpp's wave_acceleration, in float32, `precise`); R = z, G = v
class GpuSymplecticWave final : public GpuGrid {
 public:
  GpuSymplecticWave(const Context& context, int points, float c2, float mu, float dt);  // c2 = c^2 / d^2
  void set_step(float dt);
  void upload(const Eigen::VectorXf& z, const Eigen::VectorXf& v) { upload_channels(z, v); }
  void download(Eigen::VectorXf& z, Eigen::VectorXf& v) const { download_channels(z, v); }
};

// the backend the GPU methods make their contexts with: OSMesa, unless STEPWISE_GPU_BACKEND=egl; GlError
// for another value
render::Backend backend();

// "" or why a points^2 grid cannot be stepped on `context`: past its GL_MAX_TEXTURE_SIZE, or RGBA32F not
// a render target there; the limit named
std::string texture_problem(const Context& context, int points);
// the same asked of a context of the GPU methods' backend (OSMesa, or STEPWISE_GPU_BACKEND=egl), made for
// the question; a context that cannot be made is the answer
std::string grid_problem(int points);

// registers the GPU shader methods with the solvers' method table: gpu-wave (GpuWave stepping a wave scene,
// wave_fd.hpp's start and velocities around it) and gpu-symplectic-euler (GpuSymplecticWave). Each run
// makes its own context, OSMesa unless STEPWISE_GPU_BACKEND=egl
void register_gpu_methods();

}  // namespace stepwise::gpu
