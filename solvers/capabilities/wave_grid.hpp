// Capability: y = (z, v) on a square grid of points (boundary included, held at z = v = 0) for the damped
// wave equation d2z/dt2 = c^2 (5-point Laplacian of z) - mu dz/dt: the structure the seeds' three-level
// finite-difference scheme (wave_step.hpp; wave-fd, gpu-wave) and the second seed's symplectic Euler on
// the grid (gpu-symplectic-euler) need.
#pragma once

#include "solvers/ode_system.hpp"

namespace stepwise {

struct WaveGridView {
  int points = 0;       // grid points per side; z = y[0..points^2) row-major, v = y[points^2..2 points^2)
  double spacing = 0;   // d (m)
  double c = 0;         // wave speed (m/s)
  double mu = 0;        // damping (1/s)
};

inline const Requirement needs_wave_grid = needs<WaveGridView>("a wave equation on a grid (a water scene)");

}  // namespace stepwise
