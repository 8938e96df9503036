// A mass-spring cloth (seeds: the mass-spring flag): a rows x columns grid of nodes, each joined to its
// neighbours by Voigt springs (models/springs.hpp) in three families, each of which can be switched off:
//   structural: to the nodes one apart along a row or column (stretch),
//   shear:      to the diagonal neighbours (the seeds' "volume preservation"),
//   bend:       to the nodes two apart along a row or column (the seeds' "curvature"),
// four of each at an interior node, twelve in all. Rest lengths are the grid's spacing (width / (columns - 1)
// across, height / (rows - 1) down). Each node has mass `mass` / (rows columns), linear drag, gravity
// along -y, a wind acting through the cloth's normals, and one picked node may be pulled by a constant force.
//
// Wind (a linear drag law on the normal relative flow): each grid cell is two triangles; a triangle with
// area vector N = (x1 - x0) x (x2 - x0) / 2 (|N| its area) and mean corner velocity vbar feels
//   F = k_w ((w(t) - vbar) . N) N / |N|,      w(t) = w0 (1 + A sin(2 pi f t)) (a gust),
// a third on each corner: a sheet edge-on to the wind feels none, face-on the most.
//
// Pins: any of the sets the scenes need (the four corners: the seeds' flag; the left edge: a flag on a
// pole; the two top corners: a hanging sheet), one node by row and column, and any list of nodes (a
// scene's [pins] table: nodes = [[row, column], ...]; with pin_corners = 0, those alone). Pinned nodes are not part
// of the state: a spring to one is a spring from a fixed anchor.
//
// Obstacles: a sphere and the ground plane y = ground_y. After each step (its Projection capability) a node
// inside one is put back on its surface and, if moving into it, given the plane response of the
// collisions issue (models/plane_collision.hpp) without restitution, with Coulomb friction.
//
// The sheet starts flat and at rest: vertical in the x-y plane (top row at y = elevation), or horizontal in
// the x-z plane at y = elevation; centred on x = 0 (and z = 0 when horizontal).
//
// Jacobians: K = df/dx and D = df/dv on a fixed block pattern. Exact: the springs' exact derivatives, the
// wind's dependence on positions (through N) and velocities. Definite (for the Cholesky solve): the
// springs' definite approximation (springs.hpp, with its sources) and the wind's velocity part (symmetric,
// negative semidefinite); the wind's position part, which is not symmetric, is left to the explicit side.
#pragma once

#include <stepwise/models/model.hpp>

#include <span>

namespace stepwise {

std::span<const ParamSpec> cloth_params();
// pins: grid nodes pinned besides those the parameters pin
std::unique_ptr<Model> make_cloth(const Params& params, std::span<const GridNode> pins = {});

}  // namespace stepwise
