// Height-field water (seeds: height field, wave equation with viscous damping).
//
//   d2z/dt2 = c^2 (d2z/dx2 + d2z/dy2) - mu dz/dt   on the square [0, L]^2,  z = 0 on its boundary,
//
// discretised in space by the method of lines on `size` = N + 1 points per side, spacing d, L = N d, with
// the 5-point Laplacian (Lap z)_ij = (z_{i+1,j} + z_{i-1,j} + z_{i,j+1} + z_{i,j-1} - 4 z_ij) / d^2:
//
//   dz/dt = v,   dv/dt = c^2 Lap z - mu v,
//
// an ODE system every generic method runs (CVODE BDF with the sparse Jacobian and KLU), and the structure
// (wave_grid) the seeds' three-level scheme `wave-fd` steps directly.
//
// Modes: s_mn(i, j) = sin(m pi i / N) sin(n pi j / N), 1 <= m, n <= N - 1, are the Laplacian's
// eigenvectors, Lap s_mn = -lambda_mn s_mn with
//
//   lambda_mn = (4 / d^2) (sin^2(m pi / 2N) + sin^2(n pi / 2N))   (semi-discrete),
//   k_mn^2   = pi^2 (m^2 + n^2) / L^2                              (continuous; lambda_mn -> k_mn^2 as d -> 0),
//
// so a mode's amplitude obeys a'' + mu a' + c^2 lambda a = 0: a damped cosine (mode_amplitude).
//
// Energy (per unit density) E = d^2 sum v^2 / 2 + c^2 sum over grid edges (z_i - z_j)^2 / 2, the
// semi-discrete form of the integral of (v^2 + c^2 |grad z|^2) / 2: conserved when mu = 0, dissipated at
// the rate mu d^2 sum v^2.
//
// state: z on all size^2 points row-major (m), then v (m/s); boundary points stay 0. Large: trajectory.csv
// and final_state carry the summary energy, max_abs_z, max_abs_v.
//
// Scenes: water-drop (a raised-cosine drop at rest: z = h (1 + cos(pi r / R)) / 2 inside radius R),
// standing-wave (one mode, exact), pool (drops at random places and seeded random times, each an event).
#pragma once

#include <stepwise/kernels/wave_acceleration.hpp>
#include <stepwise/models/model.hpp>
#include <stepwise/solvers/capabilities/wave_grid.hpp>

namespace stepwise {

std::span<const ParamSpec> water_drop_params();
std::span<const ParamSpec> standing_wave_params();
std::span<const ParamSpec> pool_params();
std::unique_ptr<Model> make_water_drop(const Params& params);
std::unique_ptr<Model> make_standing_wave(const Params& params);
std::unique_ptr<Model> make_pool(const Params& params);

// lambda_mn of the 5-point Laplacian on N intervals of spacing d (the header's formula)
double laplacian_eigenvalue(int intervals, double spacing, int m, int n);

// the mode s_mn on size^2 points, row-major (zero on the boundary)
Eigen::VectorXd wave_mode(int points, int m, int n);
// s_mn at point (i, j)
double wave_mode_at(int points, int m, int n, int i, int j);

// the checks every water model makes of its grid: at least 3 points per side and, with `drop`, the
// scene's drop (drop_x, drop_y) strictly inside; BadParameter naming the key
void check_water_grid(const Params& p, int points, double spacing, bool drop);

// z += h (1 + cos(pi r / R)) / 2 within radius R of (x, y) on the interior of a points^2 grid of spacing d
// (the water-drop's shape, shared with the shallow water model); z holds the whole grid, or with `block` only
// that block's points (rows x cols, row-major)
void add_raised_cosine(int points, double spacing, double x, double y, double radius, double height, double* z);
void add_raised_cosine(int points, double spacing, double x, double y, double radius, double height, double* z, const GridBlock& block);

// amplitude and rate (a, a') at time t of a'' + mu a' + w2 a = 0 from a(0) = a0, a'(0) = 0
std::pair<double, double> mode_amplitude(double w2, double mu, double a0, double t);

}  // namespace stepwise
