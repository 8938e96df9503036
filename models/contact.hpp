// Contacts between convex rigid bodies and with a ground plane, and the impulses that resolve them
// (seeds: collision, the general case, for bodies that turn).
//
// Detection. Bodies are closed convex triangle meshes in their principal frames. A pair is tested only
// where the bounding spheres about the centres of mass overlap; then the collisions issue's hierarchy
// (triangle_mesh.hpp: BVH over each mesh, Moller's triangle-triangle test in overlapping leaves) gives the
// pairs of faces that cut each other, and only their features are examined:
//   - a vertex of one body inside the other (behind all its face planes): a contact at the vertex, along
//     the outward normal of the face it is least deep behind (Ericson, Real-Time Collision Detection, 5.2.1);
//   - a feature edge (between two faces that are not coplanar) of one body crossing the other with both
//     ends outside: the edge-edge case; a contact at the middle of the part inside (segment-triangle test,
//     Moller-Trumbore), along the nearest face's normal there.
// Against the ground plane a body's vertices behind the plane are its contacts.
//
// Response. At each contact the relative velocity of the two body points u = (v_a + w_a x r_a) -
// (v_b + w_b x r_b) answers an impulse j (+j on a, -j on b) linearly, u += K j, with the collision matrix
//   K = (1/m_a + 1/m_b) 1 - [r_a]x I_a^-1 [r_a]x - [r_b]x I_b^-1 [r_b]x   (world inertia I = R I_body R^T)
// (Mirtich & Canny, "Impulse-based simulation of rigid bodies", 1995; Guendelman, Bridson & Fedkiw,
// "Nonconvex rigid bodies with stacking", SIGGRAPH 2003). All contacts are solved together by projected
// Gauss-Seidel on accumulated impulses (Catto, "Iterative dynamics with temporal coherence", GDC 2005):
// per contact the normal impulse lambda_n >= 0 drives the normal velocity to its target, -eps u_n at an
// impact (approach faster than the resting speed), 0 otherwise; the tangential impulse drives the sliding
// velocity to zero, held inside Coulomb's cone |lambda_t| <= mu lambda_n. Sweeps repeat until no impulse
// changes the velocity at its contact by more than a tolerance. A resting contact starts from the impulse
// it had at the last step (warm start, Catto 2005): a stack's impulses change little from step to step,
// and Gauss-Seidel from zero needs sweeps growing with the square of the stack's height.
// The kinetic energy change of impulses is exact: dT = sum_i j_i . u_i(before) + the quadratic form of the
// j_i, computed directly from the velocities. Gauss-Seidel with restitution and friction together can
// raise it (Kane's paradox for one contact; simultaneous restitution for several): when dT > 0 the
// velocities are restored and frictionless impulses are applied one contact at a time instead, each
// j = -(1 + eps) u_n / (n.K n) n only where the contact approaches, which cannot: it changes T by
// -(1 - eps^2) u_n^2 / (2 n.K n) <= 0 for eps <= 1. The outcome says when this happened.
// Penetration left by a step is pushed out along the deepest contact of each pair that is not separating
// (resting contact), a fraction of its depth beyond a tolerance, split by inverse mass: positions only, so
// no kinetic energy is added and the centre of mass stays; the angular momentum about a point changes by
// m_a d_a x (v_a - v_b), which is why pairs that separate (after an impact) are left to do it by themselves.
#pragma once

#include "plane_collision.hpp"
#include "solvers/ode_system.hpp"
#include "triangle_mesh.hpp"

#include <Eigen/Dense>

#include <array>
#include <optional>
#include <span>
#include <vector>

namespace stepwise {

// a convex body: mesh in its principal frame (centre of mass at the origin, axes along the principal axes)
struct ContactBody {
  TriangleMesh mesh;
  Bvh bvh;                                    // over mesh, body frame
  std::vector<Plane> faces;                   // outward face planes, body frame
  std::vector<std::array<int, 2>> edges;      // feature edges (vertex pairs, first < second)
  std::vector<std::array<int, 3>> face_edges; // per face, its edges' indices in `edges`, -1 for a non-feature edge
  double mass = 0;                            // kg
  Eigen::Vector3d inertia;                    // principal moments (kg m^2)
  double radius = 0;                          // bounding sphere about the centre of mass (m)
};

// the body of uniform `density` bounded by a closed convex mesh with outward faces; `to_body` receives the
// rotation taking mesh axes to principal axes and the centre of mass (p_body = R^T (p_mesh - c)).
// Throws std::invalid_argument naming what is wrong (open, inside out, not convex, density <= 0)
struct MeshPlacement {
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // principal axes as columns, mesh frame
  Eigen::Vector3d center = Eigen::Vector3d::Zero();    // centre of mass, mesh frame
};
ContactBody make_contact_body(const TriangleMesh& mesh, double density, MeshPlacement* placement = nullptr);

struct Contact {
  int a = 0, b = -1;        // bodies; b = -1: the ground
  Eigen::Vector3d point;    // world (m)
  Eigen::Vector3d normal;   // unit, from b towards a: the direction a is pushed
  double depth = 0;         // penetration (m)
  std::array<int, 4> key{}; // (a, b, the body whose feature touches, the feature): the same contact from step to step
};

// y holds the bodies' 13-entry states (ContactBodiesView); ground may be null; exact_tests (if given)
// counts triangle-triangle tests
std::vector<Contact> find_contacts(std::span<const ContactBody> bodies, const Plane* ground, const Eigen::VectorXd& y,
                                   long* exact_tests = nullptr);

struct ContactMaterial {
  double restitution = 0;  // eps in [0, 1] at impacts
  double friction = 0;     // Coulomb's mu >= 0
  double resting_speed = 0;  // an approach no faster than this is resting contact: no bounce (m/s)
  double slop = 1e-4;      // penetration left alone (m)
  double push = 0.2;       // fraction of the rest pushed out per resolution
};

// the impulses of the contacts on y's velocities, then the push out of penetration; the sweeps start from
// the impulses memory has for the same contacts (not at impacts), and memory receives this resolution's
ContactOutcome resolve(std::span<const ContactBody> bodies, std::span<const Contact> contacts, const ContactMaterial& material,
                       Eigen::Ref<Eigen::VectorXd> y, ContactMemory& memory);

// Gauss-Seidel's sweeps stop when no impulse changed the velocity at its contact by more than this (m/s):
// a resting body creeps by at most this times the time it rests
inline constexpr double contact_velocity_tolerance = 1e-10;
// and after this many at most: Gauss-Seidel converges linearly, as slowly as 0.993 a sweep in a collapsing
// stack (measured), where 200 sweeps leave about 1e-6 m/s; a resting column of 5 warm-started needs 1 to 4
inline constexpr int contact_max_sweeps = 200;
// a kinetic energy rise from the impulses below this fraction is round-off of the sums, not a rise (the
// guard acts above it)
inline constexpr double contact_energy_roundoff = 1e-12;

// kinetic energy of the bodies, sum m |v|^2 / 2 + w . I w / 2 (J)
double kinetic_energy(std::span<const ContactBody> bodies, const Eigen::VectorXd& y);

}  // namespace stepwise
