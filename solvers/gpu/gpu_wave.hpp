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

#include "gpu_grid.hpp"
#include "solvers/wave_step.hpp"

#include <Eigen/Dense>

#include <string>

namespace stepwise::gpu {

// a square grid's two channels (R, G) in one plane of GpuGrid, the pass's GLSL main after the shared
// part (gpu_wave.cpp's grid_pass)
class GpuWaveGrid : public GpuGrid {
 public:
  GpuWaveGrid(const Context& context, int points, const char* pass, const std::string& name);

 protected:
  // the two channels, points^2 each, row-major (the CPU grids' layout)
  void upload_channels(const Eigen::VectorXf& red, const Eigen::VectorXf& green);
  void download_channels(Eigen::VectorXf& red, Eigen::VectorXf& green) const;
};

// the seeds' three-level scheme: R = z^k, G = z^{k-1}
class GpuWave final : public GpuWaveGrid {
 public:
  GpuWave(const Context& context, int points, const BasicWaveCoefficients<float>& k);
  // the coefficients of another step size
  void set_coefficients(const BasicWaveCoefficients<float>& k);
  void upload(const Eigen::VectorXf& z_prev, const Eigen::VectorXf& z) { upload_channels(z, z_prev); }
  void download(Eigen::VectorXf& z_prev, Eigen::VectorXf& z) const { download_channels(z, z_prev); }
};

// the second seed's scheme, symplectic Euler with the damping explicit: v += (c^2 Lap z - mu v) dt, then
// z += v dt (models/height_field.hpp's wave_acceleration, in float32, `precise`); R = z, G = v
class GpuSymplecticWave final : public GpuWaveGrid {
 public:
  GpuSymplecticWave(const Context& context, int points, float c2, float mu, float dt);  // c2 = c^2 / d^2
  void set_step(float dt);
  void upload(const Eigen::VectorXf& z, const Eigen::VectorXf& v) { upload_channels(z, v); }
  void download(Eigen::VectorXf& z, Eigen::VectorXf& v) const { download_channels(z, v); }
};

// registers gpu-wave (GpuWave stepping a wave scene, three_level_wave.hpp's start and velocities around it) and
// gpu-symplectic-euler (GpuSymplecticWave) with the solvers' method table
void register_wave_methods(MethodTable& table);

}  // namespace stepwise::gpu
