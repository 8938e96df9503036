#include "triangle_mesh.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace stepwise {

void validate(const TriangleMesh& mesh) {
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    if (!mesh.vertices.row(v).allFinite()) throw std::invalid_argument(fmt::format("mesh vertex {} is not finite", v));
  const auto n = mesh.vertices.rows();
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh.faces(f, k) < 0 || mesh.faces(f, k) >= n)
        throw std::invalid_argument(fmt::format("mesh face {} has vertex index {} out of range [0, {})", f, mesh.faces(f, k), n));
}

Triangle triangle(const TriangleMesh& mesh, int face) {
  return {mesh.vertices.row(mesh.faces(face, 0)).transpose(), mesh.vertices.row(mesh.faces(face, 1)).transpose(),
          mesh.vertices.row(mesh.faces(face, 2)).transpose()};
}

Aabb bounding_box(const TriangleMesh& mesh) {
  Aabb box;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) box.extend(Eigen::Vector3d(mesh.vertices.row(v).transpose()));
  return box;
}

Sphere bounding_sphere(const TriangleMesh& mesh) {
  const Eigen::Vector3d center = mesh.vertices.colwise().mean().transpose();
  double radius = 0;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) radius = std::max(radius, (mesh.vertices.row(v).transpose() - center).norm());
  return {center, radius};
}

namespace {

Aabb face_box(const TriangleMesh& mesh, int face) {
  const Triangle t = triangle(mesh, face);
  Aabb box;
  box.extend(t.a);
  box.extend(t.b);
  box.extend(t.c);
  return box;
}

int build(Bvh& bvh, const TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& centroids, int first, int count, int leaf_size) {
  const int index = static_cast<int>(bvh.nodes.size());
  bvh.nodes.emplace_back();
  Aabb box, centre_box;
  for (int k = first; k < first + count; ++k) {
    box.extend(face_box(mesh, bvh.order[k]));
    centre_box.extend(centroids[bvh.order[k]]);
  }
  bvh.nodes[index].box = box;
  if (count <= leaf_size) {
    bvh.nodes[index].first = first;
    bvh.nodes[index].count = count;
    return index;
  }
  int axis = 0;
  (centre_box.hi - centre_box.lo).maxCoeff(&axis);
  const int half = count / 2;
  std::nth_element(bvh.order.begin() + first, bvh.order.begin() + first + half, bvh.order.begin() + first + count,
                   [&](int x, int y) { return centroids[x][axis] < centroids[y][axis]; });
  const int left = build(bvh, mesh, centroids, first, half, leaf_size);
  const int right = build(bvh, mesh, centroids, first + half, count - half, leaf_size);
  bvh.nodes[index].left = left;
  bvh.nodes[index].right = right;
  return index;
}

void collect(const TriangleMesh& a, const Bvh& ba, int na, const TriangleMesh& b, const Bvh& bb, int nb, PairQuery& q) {
  const auto& x = ba.nodes[na];
  const auto& y = bb.nodes[nb];
  if (!x.box.overlaps(y.box)) return;
  if (x.count > 0 && y.count > 0) {
    for (int i = x.first; i < x.first + x.count; ++i)
      for (int j = y.first; j < y.first + y.count; ++j) {
        ++q.exact_tests;
        if (triangles_intersect(triangle(a, ba.order[i]), triangle(b, bb.order[j]))) q.pairs.emplace_back(ba.order[i], bb.order[j]);
      }
    return;
  }
  // open the larger inner node (by box diagonal) of the pair
  const bool open_x = y.count > 0 || (x.count == 0 && (x.box.hi - x.box.lo).norm() >= (y.box.hi - y.box.lo).norm());
  if (open_x) {
    collect(a, ba, x.left, b, bb, nb, q);
    collect(a, ba, x.right, b, bb, nb, q);
  } else {
    collect(a, ba, na, b, bb, y.left, q);
    collect(a, ba, na, b, bb, y.right, q);
  }
}

}  // namespace

Bvh build_bvh(const TriangleMesh& mesh, int leaf_size) {
  Bvh bvh;
  const int faces = static_cast<int>(mesh.faces.rows());
  if (faces == 0) return bvh;
  std::vector<Eigen::Vector3d> centroids(faces);
  for (int f = 0; f < faces; ++f) {
    const Triangle t = triangle(mesh, f);
    centroids[f] = (t.a + t.b + t.c) / 3;
  }
  bvh.order.resize(faces);
  std::iota(bvh.order.begin(), bvh.order.end(), 0);
  build(bvh, mesh, centroids, 0, faces, leaf_size);
  return bvh;
}

PairQuery intersecting_pairs(const TriangleMesh& a, const Bvh& bvh_a, const TriangleMesh& b, const Bvh& bvh_b) {
  PairQuery q;
  if (!bvh_a.nodes.empty() && !bvh_b.nodes.empty() && bounding_sphere(a).overlaps(bounding_sphere(b)))
    collect(a, bvh_a, 0, b, bvh_b, 0, q);
  std::sort(q.pairs.begin(), q.pairs.end());
  return q;
}

PairQuery intersecting_pairs_brute_force(const TriangleMesh& a, const TriangleMesh& b) {
  PairQuery q;
  if (!bounding_sphere(a).overlaps(bounding_sphere(b)) || !bounding_box(a).overlaps(bounding_box(b))) return q;
  for (int i = 0; i < a.faces.rows(); ++i)
    for (int j = 0; j < b.faces.rows(); ++j) {
      ++q.exact_tests;
      if (triangles_intersect(triangle(a, i), triangle(b, j))) q.pairs.emplace_back(i, j);
    }
  std::sort(q.pairs.begin(), q.pairs.end());
  return q;
}

}  // namespace stepwise
