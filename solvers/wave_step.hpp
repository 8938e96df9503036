// The seeds' explicit finite-difference scheme for the damped wave equation (height-field water)
//
//   d2z/dt2 = c^2 (d2z/dx2 + d2z/dy2) - mu dz/dt,   z = 0 on the boundary,
//
// on a square grid of spacing d, time step dt, z^k the heights at t = k dt:
//
//   z(i,j,k+1) = [ (4 - 8 c^2 dt^2/d^2) z(i,j,k) + (mu dt - 2) z(i,j,k-1)
//                  + 2 c^2 dt^2/d^2 (z(i+1,j,k) + z(i-1,j,k) + z(i,j+1,k) + z(i,j-1,k)) ] / (mu dt + 2)
//
// which is the centred second difference in time, (z^{k+1} - 2 z^k + z^{k-1}) / dt^2, equal to the
// 5-point Laplacian at k times c^2 less mu times the centred velocity (z^{k+1} - z^{k-1}) / (2 dt),
// multiplied by 2 dt^2 and solved for z^{k+1}. The division by (mu dt + 2) is folded into the three
// coefficients once (wave_coefficients), so a cell costs three multiplies and four adds.
//
// Stability (von Neumann): a mode with 5-point Laplacian eigenvalue
// -lambda obeys (2 + mu dt) r^2 - (4 - 2 c^2 dt^2 lambda) r + (2 - mu dt) = 0, whose roots lie in the unit
// disc (Jury) iff c^2 dt^2 lambda <= 4, whatever mu >= 0. With the largest eigenvalue
// lambda_max = (8/d^2) cos^2(pi / 2N) on N intervals per side: dt <= d / (sqrt(2) c cos(pi / 2N)).
#pragma once

#include <stepwise/solvers/capabilities/wave_grid.hpp>
#include <stepwise/kernels/wave_acceleration.hpp>

#include <optional>
#include <string_view>

namespace stepwise {

// the bracket's three factors, each divided by (mu dt + 2); in double, or rounded to float for the
// float32 schemes (the GPU's and its CPU reference)
template <class T>
struct BasicWaveCoefficients {
  T self = 0;        // (4 - 8 c^2 dt^2/d^2) / (mu dt + 2)
  T previous = 0;    // (mu dt - 2) / (mu dt + 2)
  T neighbours = 0;  // 2 c^2 dt^2/d^2 / (mu dt + 2)
};
using WaveCoefficients = BasicWaveCoefficients<double>;

// each factor rounded to float
inline BasicWaveCoefficients<float> to_float(const BasicWaveCoefficients<double>& k) {
  return {static_cast<float>(k.self), static_cast<float>(k.previous), static_cast<float>(k.neighbours)};
}

WaveCoefficients wave_coefficients(const WaveGridView& grid, double dt);

// the largest dt the scheme survives on this grid (the derivation above)
double wave_stable_dt(const WaveGridView& grid);

// the same for the second seed's scheme, v += (c^2 Lap z - mu v) dt, z += v dt: symplectic Euler with the
// damping explicit. Its amplification matrix for a mode of frequency w has trace 2 - dt^2 w^2 - mu dt and
// determinant 1 - mu dt; Jury's conditions give dt^2 w_max^2 + 2 mu dt <= 4 (and mu dt <= 2):
// dt <= (-mu + sqrt(mu^2 + 4 w_max^2)) / w_max^2, shorter the more damping
double symplectic_euler_wave_dt(const WaveGridView& grid);

// one cell of the update: the one formula every loop shares (the kernels below, the wave-fd stepper, the
// float32 reference of the GPU's shader, whose GLSL spells the same operations in the same order)
template <class T>
inline T wave_cell(const BasicWaveCoefficients<T>& k, T z, T z_prev, T neighbours) {
  return k.self * z + k.previous * z_prev + k.neighbours * neighbours;
}

// The three-level scheme on a state y = (z, v) (three_level_wave.hpp), per cell, shared by the stepper on
// one process and the one on a rank's block (distributed_wave.hpp), so both give the same bits:
// - v^{k+1} = (3 z^{k+1} - 4 z^k + z^{k-1}) / (2 dt), the second-order one-sided difference;
inline double wave_velocity(double h, double z1, double z, double z_prev) { return (3 * z1 - 4 * z + z_prev) / (2 * h); }
// - a restart by velocity Verlet: from a = c^2 Lap z - mu v, z^1 = z + h v + h^2/2 a and the first half of
//   v^1, v + h/2 a; then v^1 = (that + h/2 c^2 Lap z^1) / (1 + mu h / 2), the damping in a(z^1, v^1) solved for
//   (a first-order v^1 = v + h a would make a restart at every step grow)
struct VerletStart {
  double z1 = 0, v_half = 0;
};
inline VerletStart wave_restart_first(double h, double a, double z, double v) { return {z + h * v + (h * h / 2) * a, v + (h / 2) * a}; }
inline double wave_restart_second(double h, double mu, double v_half, double laplacian_z1) {
  return (v_half + (h / 2) * laplacian_z1) / (1 + mu * h / 2);
}

// one step in place: z_prev holds z^{k-1} on entry and z^{k+1} on exit (the interior; its boundary is left
// as it is), z = z^k; the rows shared among `threads` OpenMP threads (the same bits for any count). A cell
// needs z^{k-1} only where z^{k+1} goes, so two grids serve the three levels: the step reads two streams
// and writes one back into a line it has just read, where a separate z^{k+1} would first be read for its
// write (a third stream). Memory-bound on grids past the caches (bench_wave)
void wave_step(const WaveCoefficients& k, int n, double* z_prev, const double* z, int threads = 1);

// cells [first, last) of `rows` consecutive rows of a grid stored with row stride `stride` (the row above a
// row's cell is `stride` before it; z_prev and z point at the first row's cell 0): the update of wave_step,
// by the same kernels, for a grid held otherwise (a rank's block inside its halo: solvers/distributed_wave)
void wave_step_rows(const WaveCoefficients& k, int stride, int rows, int first, int last, double* z_prev, const double* z);

// `steps` steps in one pass over the grid by temporal blocking: a wavefront sweeps the rows, taking row
// i to level 1, row i-1 to level 2, ..., row i-steps+1 to level `steps`, so the steps+2 rows it works on
// stay in cache (4096 x 4096: 10 rows of each grid, 640 KB) and each grid is read and written once per
// pass instead of once per step. In place as wave_step, level s written over level s-2: the same as
// calling wave_step(k, n, z_prev, z) and wave_step(k, n, z, z_prev) in turn `steps` times, bit for bit, so
// after an even count (z_prev, z) = (z^{k+steps-1}, z^{k+steps}). With threads, the steps are shared out
// in time: worker w takes its run of levels over every row, a few rows behind worker w-1, whose progress
// it waits on (a pipeline, no redundant cells and no halo copies)
void wave_steps_blocked(const WaveCoefficients& k, int n, int steps, double* z_prev, double* z, int threads = 1);

}  // namespace stepwise
