// Contacts between convex rigid bodies and with a ground plane, and the impulses that resolve them
// (seeds: collision, the general case, for bodies that turn).
//
// Detection. Bodies are closed convex triangle meshes in their principal frames. A pair is tested only
// where the bounding spheres about the centres of mass overlap; then the collision detection's hierarchy
// (triangle_mesh.hpp: BVH over each mesh, Moller's triangle-triangle test in overlapping leaves) gives the
// pairs of faces that cut each other, and only their features are examined:
//   - a vertex of one body inside the other (behind all its face planes): a contact at the vertex, along
//     the outward normal of the face it is least deep behind (Ericson, Real-Time Collision Detection, 5.2.1);
//   - a feature edge (between two faces that are not coplanar) of one body crossing the other with both
//     ends outside: the edge-edge case; a contact at the middle of the part inside (segment-triangle test,
//     Moller-Trumbore), along the nearest face's normal there.
// Against the ground plane a body's vertices behind the plane are its contacts.
//
// The contacts' response (impulses by projected Gauss-Seidel, friction, restitution, the energy guard and the
// push out of penetration) is numerics, and sits with the method: solvers/contact_solve.hpp. A model offers
// its bodies and finds their contacts (solvers/capabilities/contact_bodies.hpp).
#pragma once

#include <stepwise/models/plane_collision.hpp>
#include <stepwise/solvers/capabilities/contact_bodies.hpp>
#include <stepwise/models/triangle_mesh.hpp>

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

// y holds the bodies' 13-entry states (ContactBodiesView); ground may be null; exact_tests (if given)
// counts triangle-triangle tests
std::vector<Contact> find_contacts(std::span<const ContactBody> bodies, const Plane* ground, const Eigen::VectorXd& y,
                                   long* exact_tests = nullptr);

// each body's mass and principal moments, what the contact solve needs of it
std::vector<BodyMass> body_masses(std::span<const ContactBody> bodies);

// kinetic energy of the bodies, sum m |v|^2 / 2 + w . I w / 2 (J)
double kinetic_energy(std::span<const ContactBody> bodies, const Eigen::VectorXd& y);

}  // namespace stepwise
