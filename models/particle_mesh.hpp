// Particles falling onto a triangle-mesh obstacle and a ground plane of any orientation (seeds: collision
// with a plane, the general case; particle against a mesh).
//
// N particles of unit mass under gravity -g e_z start in the box [-spread, spread]^2 x [drop, drop + spread].
// Two surfaces:
// - the ground: the plane n . p = offset, its normal n = (plane_nx, plane_ny, plane_nz) given by the scene
//   (normalised; a zero normal is refused), tilted if the scene wants;
// - a closed convex triangle mesh (the scene's [mesh], by default an octahedron standing on the origin),
//   with outward faces. Its signed distance is g(p) = max_f (n_f . p - c_f) over the face planes: exact
//   inside, a lower bound outside, zero exactly on the surface, so its zero crossing is the seeds' plane
//   test against whichever face the particle meets (Ericson, Real-Time Collision Detection, 2005, 5.2.1).
//   The mesh must be convex and closed; it is checked on loading.
//
// Every particle-surface pair is a falling event whose response is plane_collision's on the face met
// (restitution, Coulomb friction at the impact). A rebound slower than rest_speed ends in resting contact:
// the normal velocity is removed and the particle stays on the face, the face's normal force cancelling
// the part of gravity into it, so it slides frictionlessly along a tilted face (friction acts at impacts
// only, as the seeds' response has it). A resting particle's event function is held positive, so round-off
// on the face (1e-16 m) is not a crossing; a particle that slides off a face's edge falls again.
//
// state: positions x[i], y[i], z[i] (m), then velocities vx[i], vy[i], vz[i] (m/s).
// Energy E = sum |v_i|^2 / 2 + g z_i per unit mass: impacts take (1 - eps^2) (n . v)^2 / 2 and friction more,
// sliding keeps it.
#pragma once

#include <stepwise/models/model.hpp>
#include <stepwise/models/triangle_mesh.hpp>

namespace stepwise {

std::span<const ParamSpec> particle_mesh_params();

// the default obstacle: a regular octahedron of circumradius 0.5 m standing on its lowest vertex at the origin
TriangleMesh default_obstacle();

// throws BadParameter with key "mesh" unless the mesh is closed (every edge shared by two faces in
// opposite directions), its faces non-degenerate and outward, and convex (no vertex in front of a face)
std::unique_ptr<Model> make_particle_mesh(const Params& params, const TriangleMesh& mesh);

}  // namespace stepwise
