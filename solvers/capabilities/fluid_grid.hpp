// Capability: y = (u, v, rho) on a periodic n x n grid of side L (periodic_fft.hpp's layout), an
// incompressible flow with a passive density: the structure `stable-fluids` steps directly.
//
//   u' + (u . grad) u = -grad p + nu Lap u + b (rho - mean rho) e_y,   div u = 0,
//   rho' + u . grad rho = kappa Lap rho + s(x)
#pragma once

#include <stepwise/solvers/ode_system.hpp>

#include <span>

namespace stepwise {

struct FluidGridView {
  int points = 0;            // n per side: u = y[0, n^2), v = y[n^2, 2 n^2), rho = y[2 n^2, 3 n^2)
  double length = 0;         // L (m)
  double viscosity = 0;      // nu (m^2/s)
  double diffusivity = 0;    // kappa of the density (m^2/s)
  double buoyancy = 0;       // b (m/s^2 per unit density)
  std::span<const double> source;  // s on the grid (density per second), empty: none
};

inline const Requirement needs_fluid_grid = needs<FluidGridView>("an incompressible flow on a periodic grid (a fluid scene)");

}  // namespace stepwise
