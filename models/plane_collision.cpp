#include "plane_collision.hpp"

#include "mass_properties.hpp"

#include "kernels/collision_response.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace stepwise {

Plane make_plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  const double length = normal.norm();
  if (!(length > 0) || !std::isfinite(length) || !point.allFinite())
    throw std::invalid_argument("a plane needs a finite point and a non-zero finite normal");
  return {point, normal / length};
}

double signed_distance(const Plane& plane, const Eigen::Vector3d& p) { return (p - plane.point).dot(plane.normal); }

Side side_of(const Plane& plane, const Eigen::Vector3d& p, double tolerance) {
  const double d = signed_distance(plane, p);
  if (std::abs(d) <= tolerance) return Side::on;
  return d > 0 ? Side::positive : Side::negative;
}

std::optional<double> segment_crossing(const Plane& plane, const Eigen::Vector3d& p0, const Eigen::Vector3d& p1) {
  const double d0 = signed_distance(plane, p0), d1 = signed_distance(plane, p1);
  if ((d0 > 0 && d1 > 0) || (d0 < 0 && d1 < 0) || d0 == d1) return std::nullopt;
  return d0 / (d0 - d1);
}

Eigen::Vector3d collision_response(const Plane& plane, const Eigen::Vector3d& v, double restitution, double friction) {
  return collision_response(v, plane.normal, restitution, friction);
}

std::string plane_contact(const Plane& plane, Eigen::Ref<Eigen::Vector3d> p, Eigen::Ref<Eigen::Vector3d> v, double restitution,
                          double friction, double rest_speed) {
  const double d = signed_distance(plane, p);
  if (d > 0 && v.dot(plane.normal) >= 0) return "";
  p -= d * plane.normal;
  if (v.dot(plane.normal) < 0) v = collision_response(plane, v, restitution, friction);
  if (v.dot(plane.normal) < rest_speed) {
    v -= v.dot(plane.normal) * plane.normal;
    return "rest";
  }
  return "impact";
}

std::vector<Plane> convex_faces(const TriangleMesh& mesh) {
  // closed, with a volume and faces outward: what a solid body's mesh must be (the rigid bodies ask the same)
  mass_properties(mesh, 1.0);
  const Aabb box = bounding_box(mesh);
  const double size = (box.hi - box.lo).norm();
  std::vector<Plane> planes;
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    const Triangle t = triangle(mesh, static_cast<int>(f));
    const Eigen::Vector3d normal = area_normal(t);
    if (!(normal.norm() > 1e-12 * size * size)) throw std::invalid_argument(fmt::format("mesh triangle {} has zero area", f));
    const Plane plane = make_plane(t.a, normal);
    for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
      if (signed_distance(plane, mesh.vertices.row(v).transpose()) > 1e-9 * size)
        throw std::invalid_argument(fmt::format("mesh is not convex with outward faces: vertex {} lies in front of triangle {}", v, f));
    planes.push_back(plane);
  }
  return planes;
}

}  // namespace stepwise
