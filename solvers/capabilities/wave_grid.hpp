// Capability: y = (z, v) on a square grid of points (boundary included, held at z = v = 0) for the damped
// wave equation d2z/dt2 = c^2 (5-point Laplacian of z) - mu dz/dt: the structure the seeds' three-level
// finite-difference scheme (wave_step.hpp; wave-fd, gpu-wave) and the second seed's symplectic Euler on
// the grid (gpu-symplectic-euler) need.
#pragma once

#include <stepwise/solvers/ode_system.hpp>

#include <functional>
#include <vector>

namespace stepwise {

struct WaveGridView {
  int points = 0;       // grid points per side; z = y[0..points^2) row-major, v = y[points^2..2 points^2)
  double spacing = 0;   // d (m)
  double c = 0;         // wave speed (m/s)
  double mu = 0;        // damping (1/s)
};

// a rectangle of a grid's points: rows [row0, row0 + rows), columns [col0, col0 + cols) (a rank's block)
struct GridBlock {
  int row0 = 0, rows = 0, col0 = 0, cols = 0;
};

// What a grid split among MPI ranks (solvers/distributed_wave.hpp) needs of a water model besides the view
// above: the model cut to one block, whose state is (z, v) of the block alone (rows x cols each, row-major):
// its initial state there, and its events with their handlers applied to the block (a drop adds the cells of
// its shape that fall in it). The events' g must depend on t alone (a drop's time), so that every rank finds
// them at the same time without the others' states.
struct WaveBlocksView {
  std::function<Eigen::VectorXd(const GridBlock& block)> initial_state;
  std::function<std::vector<Event>(const GridBlock& block)> events;
};

inline const Requirement needs_wave_grid = needs<WaveGridView>("a wave equation on a grid (a water scene)");

}  // namespace stepwise
