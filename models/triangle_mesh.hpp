// Triangle meshes, their bounding volumes, and a bounding-volume hierarchy over their triangles
// (seeds: collision, the general case — exact tests only where bounding volumes overlap).
//
// The hierarchy is built top-down: a node's triangles are split at the median of their centroids along
// the longest axis of the centroids' box, down to leaves of at most leaf_size triangles. Two meshes are
// tested by descending both trees together from the roots, opening the larger node of each overlapping
// pair of boxes; triangle pairs meet the exact test (Moller 1997) only in overlapping leaves.
#pragma once

#include <stepwise/models/triangle_intersection.hpp>

#include <Eigen/Dense>

#include <utility>
#include <vector>

namespace stepwise {

struct TriangleMesh {
  Eigen::Matrix<double, Eigen::Dynamic, 3> vertices;  // #V by 3 positions (m)
  Eigen::Matrix<int, Eigen::Dynamic, 3> faces;        // #F by 3 vertex indices, counter-clockwise from outside
};

// throws std::invalid_argument naming the first face index out of range or the first non-finite vertex
void validate(const TriangleMesh& mesh);

// validate, and closed and consistently oriented: every directed edge (a, b) of a face is matched by
// exactly one (b, a) of another, so the surface bounds a volume (a mass, a signed distance); throws
// std::invalid_argument naming the first edge that is not
void validate_closed(const TriangleMesh& mesh);

Triangle triangle(const TriangleMesh& mesh, int face);

// closed meshes of simple solids, centred on the origin, faces counter-clockwise from outside:
// a box of half-extents h (12 triangles); a sphere of radius r inscribed as an icosahedron subdivided
// `subdivisions` times (20 * 4^s triangles, vertices on the sphere); a cylinder along z of radius r and
// half-height h with `segments` sides (an inscribed prism, vertices on the cylinder)
TriangleMesh box_mesh(const Eigen::Vector3d& h);
TriangleMesh sphere_mesh(double r, int subdivisions);
TriangleMesh cylinder_mesh(double r, double h, int segments);

struct Aabb {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  void extend(const Eigen::Vector3d& p) { lo = lo.cwiseMin(p); hi = hi.cwiseMax(p); }
  void extend(const Aabb& b) { lo = lo.cwiseMin(b.lo); hi = hi.cwiseMax(b.hi); }
  bool overlaps(const Aabb& b) const { return (lo.array() <= b.hi.array()).all() && (b.lo.array() <= hi.array()).all(); }
};

struct Sphere {
  Eigen::Vector3d center;
  double radius;
  bool overlaps(const Sphere& s) const { return (center - s.center).norm() <= radius + s.radius; }
};

Aabb bounding_box(const TriangleMesh& mesh);
// centred on the vertices' mean, through the farthest vertex: not the smallest sphere, but a bound
Sphere bounding_sphere(const TriangleMesh& mesh);

struct Bvh {
  struct Node {
    Aabb box;
    int left = -1, right = -1;  // children (inner node)
    int first = 0, count = 0;   // range of `order` (leaf when count > 0)
  };
  std::vector<Node> nodes;      // nodes[0] is the root
  std::vector<int> order;       // face indices, grouped by leaf
};

Bvh build_bvh(const TriangleMesh& mesh, int leaf_size = 4);

struct PairQuery {
  std::vector<std::pair<int, int>> pairs;  // (face of a, face of b) that intersect, sorted
  long exact_tests = 0;                    // triangle-triangle tests run
};

// every intersecting pair of faces between a and b, through their hierarchies
PairQuery intersecting_pairs(const TriangleMesh& a, const Bvh& bvh_a, const TriangleMesh& b, const Bvh& bvh_b);

// the same by testing all pairs, after the whole-object sphere and box tests
PairQuery intersecting_pairs_brute_force(const TriangleMesh& a, const TriangleMesh& b);

}  // namespace stepwise
