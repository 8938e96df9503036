// The seeds' wave schemes on the GPU, as solvers: they step model state, so they live here and not in
// render/, which only lends them its GL context. The three-level scheme keeps the height field's two time
// levels in one plane of the grid's size (R = z^k, G = z^{k-1}), stepped by a pass that reads plane A and
// writes plane B, then the two swap (ping-pong): a full-screen fragment pass over RGBA32F textures (the
// seeds'), or a compute pass over storage buffers whose work groups share a tile of z. A pass computes
//
//   z^{k+1} = self z^k + previous z^{k-1} + neighbours ((z_down + z_up) + (z_left + z_right))
//
// in float32, the operations of solvers/wave_step.hpp's wave_cell in the same order and marked `precise`
// (no fused multiply-adds, no reassociation), so a conforming GPU gives the bits of the float32 CPU loop
// (verification/wave_modes.hpp); the boundary holds its values, as on the CPU. Between steps that follow
// one another the state stays on the device; the methods read each new level back for the run's samples.
#pragma once

#include <stepwise/solvers/gpu/gpu_grid.hpp>
#include <stepwise/solvers/wave_step.hpp>

#include <Eigen/Dense>

#include <string>

namespace stepwise::gpu {

// how a compute pass reads z: from the buffer, five reads a cell (none); from a tile of its work group's cells
// and a one-cell halo in shared memory, loaded once a step (tile); or from a tile of both channels with a
// four-cell halo, on which a dispatch takes up to four steps (four_steps: the block read from memory once in
// four steps, its halo's cells computed by more than one work group)
enum class Tiling { none, tile, four_steps };
int steps_per_dispatch(Tiling tiling);

// a square grid's two channels (R, G) in one plane of GpuGrid, stepped by `cell` (the GLSL of a cell's step,
// gpu_wave.cpp's) in a pass of either kind, a compute pass's reads as `tiling` says
class GpuWaveGrid : public GpuGrid {
 public:
  GpuWaveGrid(const Context& context, int points, Pass pass, const char* cell, const std::string& name, Tiling tiling = Tiling::tile);

 protected:
  // the two channels, points^2 each, row-major (the CPU grids' layout)
  void upload_channels(const Eigen::VectorXf& red, const Eigen::VectorXf& green);
  void download_channels(Eigen::VectorXf& red, Eigen::VectorXf& green) const;
};

// the seeds' three-level scheme: R = z^k, G = z^{k-1}
class GpuWave final : public GpuWaveGrid {
 public:
  GpuWave(const Context& context, int points, const BasicWaveCoefficients<float>& k, Pass pass = Pass::fragment, Tiling tiling = Tiling::tile);
  // the coefficients of another step size
  void set_coefficients(const BasicWaveCoefficients<float>& k);
  void upload(const Eigen::VectorXf& z_prev, const Eigen::VectorXf& z) { upload_channels(z, z_prev); }
  void download(Eigen::VectorXf& z_prev, Eigen::VectorXf& z) const { download_channels(z, z_prev); }
};

// the second seed's scheme, symplectic Euler with the damping explicit: v += (c^2 Lap z - mu v) dt, then
// z += v dt (models/height_field.hpp's wave_acceleration, in float32, `precise`); R = z, G = v
class GpuSymplecticWave final : public GpuWaveGrid {
 public:
  GpuSymplecticWave(const Context& context, int points, float c2, float mu, float dt, Pass pass = Pass::fragment,
                    Tiling tiling = Tiling::tile);  // c2 = c^2 / d^2
  void set_step(float dt);
  void upload(const Eigen::VectorXf& z, const Eigen::VectorXf& v) { upload_channels(z, v); }
  void download(Eigen::VectorXf& z, Eigen::VectorXf& v) const { download_channels(z, v); }
};

// registers gpu-wave (GpuWave stepping a wave scene, three_level_wave.hpp's start and velocities around it) and
// gpu-symplectic-euler (GpuSymplecticWave) with the solvers' method table, and their compute twins
// gpu-wave-compute and gpu-symplectic-euler-compute
void register_wave_methods(MethodTable& table);

}  // namespace stepwise::gpu
