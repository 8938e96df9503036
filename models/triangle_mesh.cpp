#include "triangle_mesh.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
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

void validate_closed(const TriangleMesh& mesh) {
  validate(mesh);
  if (mesh.faces.rows() < 4) throw std::invalid_argument(fmt::format("a closed mesh needs at least 4 triangles, got {}", mesh.faces.rows()));
  std::map<std::pair<int, int>, int> edges;
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++edges[{mesh.faces(f, k), mesh.faces(f, (k + 1) % 3)}];
  for (const auto& [edge, count] : edges) {
    const auto reverse = edges.find({edge.second, edge.first});
    if (count != 1 || reverse == edges.end() || reverse->second != 1)
      throw std::invalid_argument(fmt::format("mesh is not closed and consistently oriented: edge {}-{} is not shared by exactly two "
                                              "faces in opposite directions", edge.first, edge.second));
  }
}

TriangleMesh box_mesh(const Eigen::Vector3d& h) {
  TriangleMesh mesh;
  mesh.vertices.resize(8, 3);
  for (int v = 0; v < 8; ++v)  // bit k of v: the sign along axis k
    mesh.vertices.row(v) << (v & 1 ? h.x() : -h.x()), (v & 2 ? h.y() : -h.y()), (v & 4 ? h.z() : -h.z());
  mesh.faces.resize(12, 3);
  mesh.faces << 0, 2, 1, 1, 2, 3,   // -z
      4, 5, 6, 5, 7, 6,             // +z
      0, 1, 4, 1, 5, 4,             // -y
      2, 6, 3, 3, 6, 7,             // +y
      0, 4, 2, 2, 4, 6,             // -x
      1, 3, 5, 3, 7, 5;             // +x
  return mesh;
}

TriangleMesh sphere_mesh(double r, int subdivisions) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> points{{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                      {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : points) p.normalize();
  std::vector<std::array<int, 3>> faces{{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                        {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                        {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    // each edge's midpoint, pushed out to the sphere, made once and shared by the edge's two faces
    std::map<std::pair<int, int>, int> midpoints;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto [it, added] = midpoints.try_emplace({key.first, key.second}, static_cast<int>(points.size()));
      if (added) points.push_back((points[a] + points[b]).normalized());
      return it->second;
    };
    std::vector<std::array<int, 3>> finer;
    for (const auto& [a, b, c] : faces) {
      const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      finer.insert(finer.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
    }
    faces = std::move(finer);
  }
  TriangleMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t v = 0; v < points.size(); ++v) mesh.vertices.row(static_cast<Eigen::Index>(v)) = r * points[v].transpose();
  mesh.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) mesh.faces.row(static_cast<Eigen::Index>(f)) << faces[f][0], faces[f][1], faces[f][2];
  return mesh;
}

TriangleMesh cylinder_mesh(double r, double h, int segments) {
  TriangleMesh mesh;
  // vertices 2k (bottom) and 2k + 1 (top) of each side, then the two cap centres
  const int n = segments, bottom = 2 * n, top = 2 * n + 1;
  mesh.vertices.resize(2 * n + 2, 3);
  for (int k = 0; k < n; ++k) {
    const double a = 2 * std::numbers::pi * k / n;
    mesh.vertices.row(2 * k) << r * std::cos(a), r * std::sin(a), -h;
    mesh.vertices.row(2 * k + 1) << r * std::cos(a), r * std::sin(a), h;
  }
  mesh.vertices.row(bottom) << 0, 0, -h;
  mesh.vertices.row(top) << 0, 0, h;
  mesh.faces.resize(4 * n, 3);
  for (int k = 0; k < n; ++k) {
    const int next = (k + 1) % n;
    mesh.faces.row(4 * k) << 2 * k, 2 * next, 2 * k + 1;
    mesh.faces.row(4 * k + 1) << 2 * k + 1, 2 * next, 2 * next + 1;
    mesh.faces.row(4 * k + 2) << bottom, 2 * next, 2 * k;
    mesh.faces.row(4 * k + 3) << top, 2 * k + 1, 2 * next + 1;
  }
  return mesh;
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
