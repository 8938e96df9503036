// What the particle models share: a reproducible random stream and checks of a particle count and seed.
#pragma once

#include <stepwise/models/model.hpp>

#include <random>

namespace stepwise {

// uniform in [0, 1) from the top 53 bits of a 64-bit Mersenne twister: the same numbers on every platform,
// unlike std's distributions, so a seed names one initial state everywhere
inline double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// the parameter `key` as a whole number of `what` (particles, grid points) whose run, at bytes_each per item
// over the state and the integrators' copies of it, fits in half this machine's memory; BadParameter
// naming the key if not
int particle_count(const Params& params, std::string_view key, double bytes_each, std::string_view what = "particles");

// two parameters that multiply (a wall's rows and columns): each a whole number, their product's memory at
// bytes_each checked as particle_count checks one; BadParameter naming both when the product does not fit
std::pair<int, int> particle_grid(const Params& params, std::string_view rows, std::string_view columns, double bytes_each,
                                  std::string_view what);

// the parameter "seed" as a whole number below 2^53
unsigned long particle_seed(const Params& params);

// the state layout every particle model shares: x[i], y[i], z[i] for i < n, then vx[i], vy[i], vz[i]
std::vector<std::string> particle_state_names(int n);
// the n point particles of a state (x, v) as balls the renderer sizes, each leaving a trail or not
std::vector<Shapes::Ball> particle_balls(const Eigen::VectorXd& y, int n, bool trail = false);

// sum |v_i|^2 / 2 + g z_i over the particles of that layout (per unit mass)
double kinetic_and_gravity(const Eigen::VectorXd& y, double g);

}  // namespace stepwise
