// Modal analysis of the height field: FFTW's DST-I, and the exact evolution of each mode under the seeds'
// three-level scheme (solvers/wave_step.hpp).
//
// On size = N + 1 points per side, z = sum_{m,n=1}^{N-1} a_mn s_mn with s_mn(i, j) = sin(m pi i/N) sin(n pi j/N)
// and a_mn = (4/N^2) sum_ij z_ij s_mn(i, j). FFTW's RODFT00 (DST-I) of logical size 2N computes
// Y_k = 2 sum_j X_j sin(pi (j+1)(k+1) / N) per dimension, so in 2-D a = DST(z) / N^2, z = DST(a) / 4, and a
// round trip scales by (2N)^2.
//
// The scheme leaves each mode on its own: (2 + mu dt) a^{k+1} = (4 - 2 c^2 dt^2 lambda) a^k + (mu dt - 2) a^{k-1},
// i.e. a^{k+1} = 2B a^k - C a^{k-1} with B = (2 - c^2 dt^2 lambda)/(2 + mu dt), C = (2 - mu dt)/(2 + mu dt),
// whose roots r = B +- sqrt(B^2 - C) give the closed form (complex pair rho e^{+-i theta}, rho = sqrt(C),
// cos theta = B / rho: a damped discrete cosine of frequency theta / dt, the discrete dispersion relation).
#pragma once

#include <stepwise/solvers/capabilities/wave_grid.hpp>

namespace stepwise {

// a field uniform in [-scale, scale] on the interior of points^2, zero on the boundary (seeded, reproducible)
Eigen::VectorXd random_wave_field(int points, double scale, unsigned seed);

// a_mn for m, n = 1..N-1, row-major ((N-1)^2 values) from z on (N+1)^2 points
Eigen::VectorXd sine_coefficients(int points, const Eigen::VectorXd& z);
// z on (N+1)^2 points (zero boundary) from the (N-1)^2 coefficients
Eigen::VectorXd from_sine_coefficients(int points, const Eigen::VectorXd& a);

// one mode's recurrence a^{k+1} = 2B a^k - C a^{k-1}
struct SchemeMode {
  long double B = 0, C = 0;
};
SchemeMode scheme_mode(const WaveGridView& grid, double dt, double lambda);

// a^k in closed form from a^0 and a^1 (long double throughout)
double scheme_mode_amplitude(const SchemeMode& mode, double a0, double a1, long k);

// theta / dt, the frequency (rad/s) the scheme gives a mode whose roots are complex
double scheme_mode_frequency(const SchemeMode& mode, double dt);

// every mode of (z^0, z^1) carried to step k by its closed form, then back on the grid
Eigen::VectorXd evolve_modes(const WaveGridView& grid, double dt, const Eigen::VectorXd& z0, const Eigen::VectorXd& z1, long k);

// the energy the scheme conserves at mu = 0, between levels z^k and z^{k+1}:
// E^{k+1/2} = d^2 sum ((z^{k+1} - z^k)/dt)^2 / 2 + c^2 sum over grid edges (z^{k+1}_i - z^{k+1}_j)(z^k_i - z^k_j) / 2;
// with mu > 0 it falls by mu d^2 sum (z^{k+1} - z^{k-1})^2 / (4 dt) per step
double scheme_energy(const WaveGridView& grid, double dt, const Eigen::VectorXd& z, const Eigen::VectorXd& z_next);

// z^{k+steps} (and z^{k+steps-1} in z_prev) by the plain kernel wave_step, from (z_prev, z) = (z^{k-1}, z^k)
void run_wave_scheme(const WaveGridView& grid, double dt, long steps, Eigen::VectorXd& z_prev, Eigen::VectorXd& z);

// the same in float32, cell by cell with wave_cell on the coefficients rounded to float: the CPU reference
// the GPU's shader (solvers/gpu/gpu_wave.hpp) must match
void run_wave_scheme_float32(const WaveGridView& grid, double dt, long steps, Eigen::VectorXf& z_prev, Eigen::VectorXf& z);

// the second seed's scheme in float32, symplectic Euler on (z, v) with the damping explicit:
// v += dt (c^2 Lap z - mu v) (models/height_field.hpp's wave_acceleration), then z += dt v; the CPU
// reference of the GPU's symplectic pass
void run_symplectic_wave_float32(const WaveGridView& grid, double dt, long steps, Eigen::VectorXf& z, Eigen::VectorXf& v);

}  // namespace stepwise
