// Capability: a cloth on a grid of nodes, the structure a node-parallel pass needs (gpu-cloth; its float32
// CPU reference solvers/cloth_grid.hpp), where MassSpringView's spring list is what a matrix assembly needs.
#pragma once

#include <stepwise/solvers/ode_system.hpp>

#include <array>
#include <vector>

namespace stepwise {

// y = (x, v) of a cloth: a rows x columns grid of nodes joined by the seeds' twelve springs (four each of
// structural: one apart along a row or column; shear: the diagonals; bend: two apart), with Voigt damping,
// lumped equal masses, linear drag, gravity along -y, a gusting wind through the normals of the grid's
// triangles, a constant force on one picked node, and a sphere and the ground as obstacles; y holds the
// free nodes (x node-major, then v), in grid order. The structure a node-parallel pass needs (each node
// gathering its own forces from its neighbours: the GPU cloth, solvers/cloth_grid.hpp), where
// MassSpringView's spring list is what a matrix assembly needs. Its forces are the model's (the model says
// how they are defined); cell (r, c)'s two triangles are (k, k + columns, k + 1) and
// (k + columns, k + columns + 1, k + 1), k = r columns + c
struct ClothGridView {
  int rows = 0, columns = 0;
  std::vector<Eigen::Vector3d> start;  // every grid node's starting place, row-major (a pinned node stays there)
  std::vector<int> free_index;         // grid node -> its node in y, -1 if pinned
  double across = 0, down = 0;         // rest lengths along a row and down a column (m)
  std::array<double, 3> stiffness{};   // structural, shear, bend c (N/m); a family switched off: no spring at all
  std::array<bool, 3> family{};        // which families are on
  double damping = 0;                  // gamma along every spring (N s/m)
  double node_mass = 0;                // kg
  double drag = 0;                     // 1/s
  double g = 0;                        // m/s^2, along -y
  Eigen::Vector3d wind = Eigen::Vector3d::Zero();  // w0 (m/s); w(t) = w0 (1 + gust_amplitude sin(2 pi gust_frequency t))
  double wind_coefficient = 0, gust_amplitude = 0, gust_frequency = 0;
  int picked = -1;                     // grid node the pick force pulls, -1 for none
  Eigen::Vector3d pick_force = Eigen::Vector3d::Zero();
  double sphere_radius = 0;            // 0: no sphere
  Eigen::Vector3d sphere_centre = Eigen::Vector3d::Zero();
  bool ground = false;
  double ground_y = 0, friction = 0;
};

inline const Requirement needs_cloth_grid = needs<ClothGridView>("a cloth on a grid (a cloth scene)");

}  // namespace stepwise
