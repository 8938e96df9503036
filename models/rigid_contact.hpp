// Rigid bodies in contact with each other and with the ground (seeds: "collapse in angry birds"): convex
// bodies of uniform density, each a rigid body as rigid_body.hpp describes it, under gravity; their
// contacts (models/contact.hpp) are resolved by impulses, so f holds only the smooth part:
//   dx/dt = v,  dv/dt = (0, 0, -g),  dq/dt = q (x) (0, w) / 2,  I dw/dt = (I w) x w
// and a method that resolves contacts (sequential-impulses) steps it.
// The ground is the plane through the origin whose normal is e_z turned by ground_slope about the y axis,
// n = (sin s, 0, cos s): on a slope a body slides down +x. With ground = 0 there is none, and bodies meet
// only each other (with g = 0: momentum is conserved).
//
// State: per body the 13 entries of RigidBodyView (x, v, q, w; w in the body's principal frame), named
// x, y, z, vx, ... wz for one body and x[i], ... wz[i] for several. summary.json's final_state adds the
// energy (kinetic + m g z), the kinetic energy, the linear momentum px, py, pz and the angular momentum
// about the origin Lx, Ly, Lz (sum of x_i x m_i v_i + R_i I_i w_i).
//
// Models:
// - dropped-body: one body, a box of half-extents hx, hy, hz or the scene's convex [mesh], dropped with a
//   spin (angular velocity given in the world frame) on the ground;
// - box-stack: a wall of rows x columns boxes standing on the ground, and a projectile (an icosphere)
//   thrown at it from projectile_distance so that it meets the wall's plane at projectile_height.
#pragma once

#include <stepwise/models/model.hpp>
#include <stepwise/models/triangle_mesh.hpp>

namespace stepwise {

std::span<const ParamSpec> dropped_body_params();
std::span<const ParamSpec> box_stack_params();
// throws BadParameter with key "mesh" for a mesh that is open, inside out or not convex
std::unique_ptr<Model> make_dropped_body(const Params& params, const TriangleMesh* mesh);
std::unique_ptr<Model> make_box_stack(const Params& params);

}  // namespace stepwise
