// Collision of a particle with a plane (seeds: "collision with a plane", the general case).
//
//   signed distance   d(p) = (p - p0) . n          (n the unit normal; d > 0 on the side n points to)
//   three cases       d = 0 on the plane, d > 0 positive side, d < 0 negative side
//   crossing          on the segment p(t) -> p(t + dt), d is linear: s = d0 / (d0 - d1), p* = p0 + s (p1 - p0)
//   response          n . v2 = -eps n . v1 (eps in [0, 1]); the tangential velocity is kept, less Coulomb
//                     friction: the impulse along n is J = (1 + eps) |n . v1|, so the tangential speed drops
//                     by mu J, but never below zero (friction stops sliding, it does not reverse it)
#pragma once

#include <stepwise/models/triangle_mesh.hpp>

#include <Eigen/Dense>

#include <optional>
#include <string>
#include <vector>

namespace stepwise {

struct Plane {
  Eigen::Vector3d point;   // any point p0 on the plane (m)
  Eigen::Vector3d normal;  // unit normal n
};

// a plane through `point` with normal along `normal` (normalised); throws std::invalid_argument for a
// zero or non-finite normal
Plane make_plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal);

double signed_distance(const Plane& plane, const Eigen::Vector3d& p);

enum class Side { on, positive, negative };

// which side of the plane p lies on; |d| <= tolerance counts as on it
Side side_of(const Plane& plane, const Eigen::Vector3d& p, double tolerance = 0);

// fraction s in [0, 1] of the segment p0 -> p1 where it crosses the plane, if it does
std::optional<double> segment_crossing(const Plane& plane, const Eigen::Vector3d& p0, const Eigen::Vector3d& p1);

// velocity after an impact with the plane: restitution eps in [0, 1], Coulomb friction coefficient mu >= 0
Eigen::Vector3d collision_response(const Plane& plane, const Eigen::Vector3d& v, double restitution, double friction);

// a particle at p with velocity v meets the plane (an event handler's whole work): "" when it is still in
// front and moving away (the crossing was estimated too early); else it is moved onto the plane and, if
// moving into it, given the response; a rebound slower than rest_speed (0: never) loses its normal velocity
// and rests on the plane ("rest"), else "impact". On an axis-aligned plane through a grid value, p and v
// land on it exactly (d n and (v . n) n have one non-zero component)
std::string plane_contact(const Plane& plane, Eigen::Ref<Eigen::Vector3d> p, Eigen::Ref<Eigen::Vector3d> v, double restitution,
                          double friction, double rest_speed);

// the face planes of a closed convex mesh with outward faces, in face order; throws std::invalid_argument
// naming the first open edge, zero-area triangle, or vertex in front of a face
std::vector<Plane> convex_faces(const TriangleMesh& mesh);

}  // namespace stepwise
