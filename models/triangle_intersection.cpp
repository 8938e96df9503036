#include "triangle_intersection.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace stepwise {
namespace {

// relative size below which a distance to a plane counts as zero: a few ulps of the coordinates involved
constexpr double plane_epsilon = 64 * std::numeric_limits<double>::epsilon();

double extent(const Triangle& t) {
  return std::max({t.a.cwiseAbs().maxCoeff(), t.b.cwiseAbs().maxCoeff(), t.c.cwiseAbs().maxCoeff(), 1e-300});
}

// 2-D: do segments p-q and r-s intersect (touching included)?
bool segments_intersect_2d(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& r, const Eigen::Vector2d& s) {
  auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); };
  auto on_segment = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& x) {
    return std::min(a.x(), b.x()) <= x.x() && x.x() <= std::max(a.x(), b.x()) && std::min(a.y(), b.y()) <= x.y() &&
           x.y() <= std::max(a.y(), b.y());
  };
  const double d1 = cross(s - r, p - r), d2 = cross(s - r, q - r), d3 = cross(q - p, r - p), d4 = cross(q - p, s - p);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  return (d1 == 0 && on_segment(r, s, p)) || (d2 == 0 && on_segment(r, s, q)) || (d3 == 0 && on_segment(p, q, r)) ||
         (d4 == 0 && on_segment(p, q, s));
}

// 2-D: is x inside triangle (a, b, c) or on its boundary?
bool point_in_triangle_2d(const Eigen::Vector2d& x, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  auto side = [](const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& r) {
    return (q.x() - p.x()) * (r.y() - p.y()) - (q.y() - p.y()) * (r.x() - p.x());
  };
  const double s1 = side(a, b, x), s2 = side(b, c, x), s3 = side(c, a, x);
  return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

bool coplanar_intersect(const Eigen::Vector3d& n, const Triangle& t1, const Triangle& t2) {
  // drop the coordinate where the normal is largest
  int drop = 0;
  n.cwiseAbs().maxCoeff(&drop);
  const int i = drop == 0 ? 1 : 0, j = drop == 2 ? 1 : 2;
  auto flat = [i, j](const Eigen::Vector3d& p) { return Eigen::Vector2d(p[i], p[j]); };
  const std::array<Eigen::Vector2d, 3> v{flat(t1.a), flat(t1.b), flat(t1.c)}, u{flat(t2.a), flat(t2.b), flat(t2.c)};
  for (int e = 0; e < 3; ++e)
    for (int f = 0; f < 3; ++f)
      if (segments_intersect_2d(v[e], v[(e + 1) % 3], u[f], u[(f + 1) % 3])) return true;
  return point_in_triangle_2d(v[0], u[0], u[1], u[2]) || point_in_triangle_2d(u[0], v[0], v[1], v[2]);
}

// Moller's NEWCOMPUTE_INTERVALS: the interval of a triangle on L as a fraction-free (a, b, c, x0, x1);
// false when all distances vanish (coplanar)
bool interval(double p0, double p1, double p2, double d0, double d1, double d2, double& a, double& b, double& c,
              double& x0, double& x1) {
  if (d0 * d1 > 0) { a = p2; b = (p0 - p2) * d2; c = (p1 - p2) * d2; x0 = d2 - d0; x1 = d2 - d1; }
  else if (d0 * d2 > 0) { a = p1; b = (p0 - p1) * d1; c = (p2 - p1) * d1; x0 = d1 - d0; x1 = d1 - d2; }
  else if (d1 * d2 > 0 || d0 != 0) { a = p0; b = (p1 - p0) * d0; c = (p2 - p0) * d0; x0 = d0 - d1; x1 = d0 - d2; }
  else if (d1 != 0) { a = p1; b = (p0 - p1) * d1; c = (p2 - p1) * d1; x0 = d1 - d0; x1 = d1 - d2; }
  else if (d2 != 0) { a = p2; b = (p0 - p2) * d2; c = (p1 - p2) * d2; x0 = d2 - d0; x1 = d2 - d1; }
  else return false;
  return true;
}

}  // namespace

Eigen::Vector3d area_normal(const Triangle& t) { return (t.b - t.a).cross(t.c - t.a); }

bool triangles_intersect(const Triangle& t1, const Triangle& t2) {
  const Eigen::Vector3d n1_raw = area_normal(t1), n2_raw = area_normal(t2);
  const double scale = std::max(extent(t1), extent(t2));
  // a zero-area triangle intersects nothing
  if (n1_raw.norm() <= plane_epsilon * scale * scale || n2_raw.norm() <= plane_epsilon * scale * scale) return false;
  const Eigen::Vector3d n1 = n1_raw.normalized(), n2 = n2_raw.normalized();
  auto distance = [scale](const Eigen::Vector3d& n, const Eigen::Vector3d& origin, const Eigen::Vector3d& p) {
    const double d = n.dot(p - origin);
    return std::abs(d) <= plane_epsilon * scale ? 0.0 : d;
  };

  // t2's vertices against t1's plane, then t1's against t2's: all on one side, no intersection
  const double du0 = distance(n1, t1.a, t2.a), du1 = distance(n1, t1.a, t2.b), du2 = distance(n1, t1.a, t2.c);
  if (du0 * du1 > 0 && du0 * du2 > 0) return false;
  const double dv0 = distance(n2, t2.a, t1.a), dv1 = distance(n2, t2.a, t1.b), dv2 = distance(n2, t2.a, t1.c);
  if (dv0 * dv1 > 0 && dv0 * dv2 > 0) return false;

  // project onto the largest axis of the intersection line's direction
  int axis = 0;
  n1.cross(n2).cwiseAbs().maxCoeff(&axis);
  double a, b, c, x0, x1, d, e, f, y0, y1;
  if (!interval(t1.a[axis], t1.b[axis], t1.c[axis], dv0, dv1, dv2, a, b, c, x0, x1)) return coplanar_intersect(n1, t1, t2);
  if (!interval(t2.a[axis], t2.b[axis], t2.c[axis], du0, du1, du2, d, e, f, y0, y1)) return coplanar_intersect(n1, t1, t2);

  const double xx = x0 * x1, yy = y0 * y1, xxyy = xx * yy;
  std::array<double, 2> i1{a * xxyy + b * x1 * yy, a * xxyy + c * x0 * yy};
  std::array<double, 2> i2{d * xxyy + e * xx * y1, d * xxyy + f * xx * y0};
  if (i1[0] > i1[1]) std::swap(i1[0], i1[1]);
  if (i2[0] > i2[1]) std::swap(i2[0], i2[1]);
  return !(i1[1] < i2[0] || i2[1] < i1[0]);
}

std::optional<double> segment_triangle(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Triangle& t) {
  const Eigen::Vector3d dir = p1 - p0, e1 = t.b - t.a, e2 = t.c - t.a;
  const Eigen::Vector3d pvec = dir.cross(e2);
  const double det = e1.dot(pvec);
  const double scale = std::max({extent(t), p0.cwiseAbs().maxCoeff(), p1.cwiseAbs().maxCoeff()});
  if (std::abs(det) <= plane_epsilon * scale * scale * scale) return std::nullopt;  // parallel, or zero area
  const Eigen::Vector3d tvec = p0 - t.a;
  const double u = tvec.dot(pvec) / det;
  if (u < 0 || u > 1) return std::nullopt;
  const Eigen::Vector3d qvec = tvec.cross(e1);
  const double v = dir.dot(qvec) / det;
  if (v < 0 || u + v > 1) return std::nullopt;
  const double s = e2.dot(qvec) / det;
  if (s < 0 || s > 1) return std::nullopt;
  return s;
}

}  // namespace stepwise
