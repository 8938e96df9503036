// Exact tests between triangles and between a segment and a triangle (seeds: collision, the general case).
//
// triangles_intersect: Moller, "A fast triangle-triangle intersection test", JGT 2(2), 1997, the
// division-free variant. Each triangle's vertices are put into the other's plane equation; if all three
// lie strictly on one side there is no intersection. Otherwise both triangles cut the line L = N1 x N2,
// and they intersect iff their intervals on L overlap. Coplanar triangles are tested in 2-D, projected on
// the axis plane where their normal is largest: any pair of edges crossing, or one triangle containing a
// vertex of the other.
// Defined answers for degenerate input: touching (a shared vertex or edge, a vertex on a face) counts as
// intersecting; a zero-area triangle intersects nothing.
//
// segment_triangle: Moller and Trumbore, "Fast, minimum storage ray/triangle intersection", JGT 2(1), 1997:
// p(s) = p0 + s (p1 - p0) = (1 - u - v) A + u B + v C solved by Cramer's rule, a hit when s, u, v, 1 - u - v >= 0
// and s <= 1. A particle moving from p0 to p1 over a step crosses the triangle at fraction s.
#pragma once

#include <Eigen/Dense>

#include <optional>

namespace stepwise {

struct Triangle {
  Eigen::Vector3d a, b, c;  // vertices (m)
};

// twice the area's vector: (b - a) x (c - a)
Eigen::Vector3d area_normal(const Triangle& t);

bool triangles_intersect(const Triangle& t1, const Triangle& t2);

// fraction s in [0, 1] of the segment p0 -> p1 where it meets the triangle; none when it misses, is
// parallel to it, or the triangle has zero area
std::optional<double> segment_triangle(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Triangle& t);

}  // namespace stepwise
