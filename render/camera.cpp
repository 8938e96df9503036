#include "camera.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace stepwise::render {

Eigen::Matrix4f Camera::view_projection(double aspect) const {
  // look-at: rows are the camera's right, up and backward axes
  const Eigen::Vector3d back = (eye - target).normalized();
  const Eigen::Vector3d right = up.cross(back).normalized();
  const Eigen::Vector3d true_up = back.cross(right);
  Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
  view.block<1, 3>(0, 0) = right.transpose();
  view.block<1, 3>(1, 0) = true_up.transpose();
  view.block<1, 3>(2, 0) = back.transpose();
  view.block<3, 1>(0, 3) = -view.block<3, 3>(0, 0) * eye;
  // perspective (OpenGL clip space, depth -1..1)
  const double f = 1 / std::tan(fov_deg * std::numbers::pi / 360);
  Eigen::Matrix4d projection = Eigen::Matrix4d::Zero();
  projection(0, 0) = f / aspect;
  projection(1, 1) = f;
  projection(2, 2) = (far + near) / (near - far);
  projection(2, 3) = 2 * far * near / (near - far);
  projection(3, 2) = -1;
  return (projection * view).cast<float>();
}

Eigen::Vector2d Camera::pixel(const Eigen::Vector3d& p, int width, int height) const {
  const Eigen::Vector4d clip = view_projection(static_cast<double>(width) / height).cast<double>() * p.homogeneous();
  const Eigen::Vector2d ndc = clip.head<2>() / clip.w();
  return {(ndc.x() + 1) / 2 * width, (1 - ndc.y()) / 2 * height};
}

namespace {

// the bodies' vertices (world), the sheets' vertices and the rods' points
void for_solid_points(const Shapes& shapes, const std::function<void(const Eigen::Vector3d&)>& visit) {
  for (const auto& body : shapes.bodies)
    for (Eigen::Index v = 0; v < body.mesh->vertices.rows(); ++v) visit(body.rotation * body.mesh->vertices.row(v).transpose() + body.position);
  for (const auto& sheet : shapes.surfaces)
    for (Eigen::Index v = 0; v < sheet.vertices.rows(); ++v) visit(sheet.vertices.row(v).transpose());
  for (const auto& line : shapes.lines)
    for (const auto& p : line) visit(p);
}

}  // namespace

void for_each_point(const Shapes& shapes, const std::function<void(const Eigen::Vector3d&)>& visit) {
  for (const auto& ball : shapes.balls) visit(ball.center);
  for_solid_points(shapes, visit);
  if (const auto& w = shapes.water)
    for (int i = 0; i < w->points; ++i)
      for (int j = 0; j < w->points; ++j) visit({j * w->spacing, i * w->spacing, w->z[i * w->points + j]});
}

double pixel_distance(const Shapes& a, const Shapes& b, const Camera& camera, int width, int height) {
  std::vector<Eigen::Vector2d> at;
  for_each_point(a, [&](const Eigen::Vector3d& p) { at.push_back(camera.pixel(p, width, height)); });
  size_t k = 0;
  double largest = 0;
  bool finite = true;
  for_each_point(b, [&](const Eigen::Vector3d& p) {
    const double d = k < at.size() ? (camera.pixel(p, width, height) - at[k]).norm() : NAN;
    finite = finite && std::isfinite(d);
    largest = std::max(largest, d);
    ++k;
  });
  return finite && k == at.size() ? largest : NAN;
}

Aabb bounds(const Shapes& shapes, double depth) {
  Aabb box;
  for (const auto& ball : shapes.balls) {
    box.extend(ball.center.array() - ball.radius);
    box.extend(ball.center.array() + ball.radius);
  }
  for_solid_points(shapes, [&](const Eigen::Vector3d& p) { box.extend(p); });
  if (shapes.container) {
    box.extend(shapes.container->lo);
    box.extend(shapes.container->hi);
  }
  for (const auto& field : shapes.fields) {
    box.extend(Eigen::Vector3d(field.origin.x(), field.origin.y(), 0));
    box.extend(Eigen::Vector3d(field.origin.x() + field.extent.x(), field.origin.y() + field.extent.y(), 0));
  }
  if (shapes.water) {
    const Pool pool(*shapes.water, depth);
    box.extend(Eigen::Vector3d(-pool.border, -pool.border, -depth));
    box.extend(Eigen::Vector3d(pool.side + pool.border, pool.side + pool.border, std::max(pool.rim, shapes.water->z.maxCoeff())));
  }
  return box;
}

double pool_depth(const Shapes& shapes, const Look& look) {
  if (look.pool_depth) return *look.pool_depth;
  return shapes.water ? (shapes.water->points - 1) * shapes.water->spacing / 4 : 0;
}

Camera frame_camera(const Aabb& box, const Shapes& shapes, const Look& look, double aspect) {
  Camera camera;
  camera.fov_deg = look.fov_deg;
  camera.up = look.up.value_or(shapes.up).normalized();
  const Eigen::Vector3d center = (box.lo + box.hi) / 2;
  const double radius = std::max(0.5 * (box.hi - box.lo).norm(), 1e-3);
  camera.target = look.target.value_or(center);
  // the direction the camera sits in: +z for a planar scene; otherwise in front (a horizontal axis of the
  // world turned 35 degrees about up) and 25 degrees above, 50 over water (to see into the pool)
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  if (!shapes.planar) {
    Eigen::Vector3d front = camera.up.cross(Eigen::Vector3d::UnitX());
    if (front.norm() < 0.5) front = camera.up.cross(Eigen::Vector3d::UnitY());
    front = -front.normalized();
    const Eigen::Vector3d side = camera.up.cross(front);
    const double azimuth = 35 * std::numbers::pi / 180, elevation = (shapes.water ? 50 : 25) * std::numbers::pi / 180;
    direction = std::cos(elevation) * (std::cos(azimuth) * front + std::sin(azimuth) * side) + std::sin(elevation) * camera.up;
  }
  // far enough that every corner of the box lies inside 95% of each half-field: a corner at (x, y) across
  // and z towards the camera from the target, seen from distance d, needs d >= z + |x| / tan(half-width)
  // (and likewise y with the half-height)
  const double tan_v = std::tan(camera.fov_deg * std::numbers::pi / 360), tan_h = aspect * tan_v, margin = 0.95;
  const Eigen::Vector3d back = direction.normalized(), right = camera.up.cross(back).normalized(), true_up = back.cross(right);
  double fit = 1e-3;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d corner((k & 1 ? box.hi : box.lo).x(), (k & 2 ? box.hi : box.lo).y(), (k & 4 ? box.hi : box.lo).z());
    const Eigen::Vector3d r = corner - camera.target;
    fit = std::max({fit, r.dot(back) + std::abs(r.dot(right)) / (margin * tan_h), r.dot(back) + std::abs(r.dot(true_up)) / (margin * tan_v)});
  }
  camera.eye = look.eye.value_or(camera.target + back * fit);
  const double distance = (camera.eye - camera.target).norm();
  camera.near = std::max(1e-4, (distance - 2 * radius) * 0.5);
  camera.far = distance + 4 * radius;
  return camera;
}

Eigen::Vector3d light_direction(const Camera& camera, const Look& look) {
  if (look.light) return look.light->normalized();
  const Eigen::Vector3d back = (camera.eye - camera.target).normalized();
  const Eigen::Vector3d left = back.cross(camera.up).normalized();
  return (1.6 * camera.up + 0.6 * left + 0.5 * back).normalized();
}

}  // namespace stepwise::render
