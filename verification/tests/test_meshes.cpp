// Triangle-triangle and segment-triangle tests on known and degenerate cases, against an independent
// criterion on random pairs, and the bounding-volume hierarchy against brute force on random meshes.
#include "models/triangle_mesh.hpp"

#include <gtest/gtest.h>

#include <random>

namespace stepwise {
namespace {

using V = Eigen::Vector3d;

TEST(Triangles, KnownAndDegenerateCasesHaveDefinedAnswers) {
  const Triangle base{V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  EXPECT_TRUE(triangles_intersect(base, {V(0.2, 0.2, -1), V(0.2, 0.2, 1), V(0.9, 0.9, 0.5)})) << "piercing";
  EXPECT_FALSE(triangles_intersect(base, {V(0, 0, 1), V(1, 0, 1), V(0, 1, 1)})) << "parallel, apart";
  EXPECT_FALSE(triangles_intersect(base, {V(2, 2, -1), V(2, 2, 1), V(3, 3, 0)})) << "planes cross, triangles apart";
  EXPECT_TRUE(triangles_intersect(base, {V(1, 0, 0), V(0, 1, 0), V(1, 1, 1)})) << "shared edge touches";
  EXPECT_TRUE(triangles_intersect(base, {V(1, 0, 0), V(2, 0, 1), V(2, 1, 1)})) << "shared vertex touches";
  EXPECT_TRUE(triangles_intersect(base, {V(0.2, 0.2, 0), V(0.2, 0.3, 1), V(0.3, 0.2, 1)})) << "vertex on the face";
  EXPECT_TRUE(triangles_intersect(base, {V(0.5, 0.5, 0), V(-0.5, 0.2, 0), V(0.2, -0.5, 0)})) << "coplanar, overlapping";
  EXPECT_TRUE(triangles_intersect(base, {V(0.1, 0.1, 0), V(0.3, 0.1, 0), V(0.1, 0.3, 0)})) << "coplanar, contained";
  EXPECT_FALSE(triangles_intersect(base, {V(2, 2, 0), V(3, 2, 0), V(2, 3, 0)})) << "coplanar, apart";
  EXPECT_FALSE(triangles_intersect(base, {V(0.2, 0.2, -1), V(0.2, 0.2, 1), V(0.2, 0.2, 0)})) << "zero area (a segment)";
  EXPECT_FALSE(triangles_intersect({V(0, 0, 0), V(0, 0, 0), V(0, 0, 0)}, base)) << "zero area (a point)";
}

TEST(Triangles, SegmentCrossingIsWhereTheParticlePassesTheFace) {
  const Triangle t{V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  const auto s = segment_triangle(V(0.25, 0.25, 1), V(0.25, 0.25, -3), t);
  ASSERT_TRUE(s.has_value());
  EXPECT_DOUBLE_EQ(*s, 0.25);
  EXPECT_FALSE(segment_triangle(V(0.9, 0.9, 1), V(0.9, 0.9, -1), t).has_value()) << "misses the face";
  EXPECT_FALSE(segment_triangle(V(0.2, 0.2, 2), V(0.2, 0.2, 1), t).has_value()) << "stops short";
  EXPECT_FALSE(segment_triangle(V(0, 0, 1), V(1, 1, 1), t).has_value()) << "parallel";
}

Triangle random_triangle(std::mt19937_64& rng, double size) {
  std::uniform_real_distribution<double> u(0, 1), d(-size, size);
  const V c(u(rng), u(rng), u(rng));
  return {c + V(d(rng), d(rng), d(rng)), c + V(d(rng), d(rng), d(rng)), c + V(d(rng), d(rng), d(rng))};
}

TEST(Triangles, AgreeWithTheEdgeCrossingCriterionOnRandomPairs) {
  // two triangles in general position intersect iff an edge of one passes through the other
  std::mt19937_64 rng(3);
  int hits = 0;
  for (int k = 0; k < 20000; ++k) {
    const Triangle a = random_triangle(rng, 0.3), b = random_triangle(rng, 0.3);
    bool edge = false;
    for (const auto& [x, y] : {std::pair{&a, &b}, std::pair{&b, &a}})
      for (const auto& [p, q] : {std::pair{x->a, x->b}, std::pair{x->b, x->c}, std::pair{x->c, x->a}})
        edge = edge || segment_triangle(p, q, *y).has_value();
    const bool moller = triangles_intersect(a, b);
    hits += moller;
    ASSERT_EQ(moller, edge) << "pair " << k;
  }
  std::cout << hits << " of 20000 random pairs intersect\n";
  EXPECT_GT(hits, 100);
}

TriangleMesh soup(unsigned seed, int count, double size) {
  std::mt19937_64 rng(seed);
  TriangleMesh mesh;
  mesh.vertices.resize(3 * count, 3);
  mesh.faces.resize(count, 3);
  for (int f = 0; f < count; ++f) {
    const Triangle t = random_triangle(rng, size);
    mesh.vertices.row(3 * f) = t.a.transpose();
    mesh.vertices.row(3 * f + 1) = t.b.transpose();
    mesh.vertices.row(3 * f + 2) = t.c.transpose();
    mesh.faces.row(f) << 3 * f, 3 * f + 1, 3 * f + 2;
  }
  return mesh;
}

TEST(Bvh, FindsExactlyTheBruteForcePairsWithFarFewerExactTests) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    const TriangleMesh a = soup(seed, 400, 0.05), b = soup(seed + 100, 400, 0.05);
    const PairQuery brute = intersecting_pairs_brute_force(a, b);
    const PairQuery fast = intersecting_pairs(a, build_bvh(a), b, build_bvh(b));
    EXPECT_EQ(fast.pairs, brute.pairs) << "seed " << seed;
    std::cout << "seed " << seed << ": " << brute.pairs.size() << " intersecting pairs; exact tests " << fast.exact_tests
              << " through the hierarchy against " << brute.exact_tests << " (" << 100.0 * fast.exact_tests / brute.exact_tests
              << "%)\n";
    EXPECT_GT(brute.pairs.size(), 0u);
    EXPECT_LT(fast.exact_tests, brute.exact_tests / 10);
  }
}

TEST(Bvh, DisjointObjectsAreRejectedByTheirBoundingVolumesAlone) {
  TriangleMesh a = soup(5, 100, 0.05), b = soup(6, 100, 0.05);
  b.vertices.col(0).array() += 10.0;
  EXPECT_EQ(intersecting_pairs(a, build_bvh(a), b, build_bvh(b)).exact_tests, 0);
  EXPECT_EQ(intersecting_pairs_brute_force(a, b).exact_tests, 0);
}

TEST(Meshes, BadMeshesAreNamed) {
  TriangleMesh mesh = soup(7, 3, 0.1);
  EXPECT_NO_THROW(validate(mesh));
  mesh.faces(1, 2) = 9;
  try {
    validate(mesh);
    FAIL() << "index out of range accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("face 1"), std::string::npos) << e.what();
  }
  mesh = soup(7, 3, 0.1);
  mesh.vertices(4, 1) = std::nan("");
  EXPECT_THROW(validate(mesh), std::invalid_argument);
}

}  // namespace
}  // namespace stepwise
