// Rigid bodies: polyhedral mass properties against closed forms (box, sphere meshes converging at second
// order, the n-sided prism exactly, an off-centre rotated body and the parallel-axis theorem); the
// torque-free body's invariants per method; the intermediate-axis flip against its elliptic-function
// period; the stable axes; a falling body against the projectile's exact solution.
#include "models/mass_properties.hpp"
#include "models/rigid_body.hpp"
#include "verification/measure.hpp"
#include "verification/order_fit.hpp"
#include "verification/tolerances.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>

namespace stepwise {
namespace {

constexpr double eps = std::numeric_limits<double>::epsilon();
using std::numbers::pi;

double relative(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) { return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff(); }

TEST(MassProperties, BoxMatchesItsClosedFormToRoundOff) {
  const Eigen::Vector3d h(0.5, 1.0, 1.5);
  const double density = 2.0;
  const MassProperties m = mass_properties(box_mesh(h), density);
  const double mass = density * 8 * h.prod();
  EXPECT_NEAR(m.mass / mass, 1, tolerance::mass_properties_roundoff);
  EXPECT_LT(m.center.norm(), tolerance::mass_properties_roundoff * h.norm());
  const Eigen::Vector3d s = h.cwiseProduct(h);
  const Eigen::Matrix3d expected = Eigen::Vector3d(s.y() + s.z(), s.x() + s.z(), s.x() + s.y()).asDiagonal() * (mass / 3);
  EXPECT_LT(relative(m.inertia, expected), tolerance::mass_properties_roundoff);
}

TEST(MassProperties, PrismMatchesTheRegularPolygonsClosedFormAndTendsToTheCylinder) {
  // a regular n-gon of circumradius r is n triangles at the centre with apex angle a = 2 pi/n: its polar
  // moment per unit mass is r^2 (2 + cos a)/6; the prism of half-height h adds h^2/3 about x and y
  const double r = 0.3, h = 0.8;
  for (const int n : {3, 6, 32, 256}) {
    const MassProperties m = mass_properties(cylinder_mesh(r, h, n), 1.0);
    const double a = 2 * pi / n;
    EXPECT_NEAR(m.volume / (n * r * r * std::sin(a) / 2 * 2 * h), 1, tolerance::mass_properties_roundoff) << n;
    const double polar = r * r * (2 + std::cos(a)) / 6;
    const Eigen::Matrix3d expected = Eigen::Vector3d(polar / 2 + h * h / 3, polar / 2 + h * h / 3, polar).asDiagonal() * m.mass;
    EXPECT_LT(relative(m.inertia, expected), tolerance::mass_properties_roundoff) << n;
  }
  // and the cylinder's m r^2/2, m (3 r^2 + 4 h^2)/12 as n grows: the polygon's area sin(a)/a and moment
  // (2 + cos a)/3 fall short by a^2/6 each, so the moments by at most a^2/3 < a^2
  const int n = 4096;
  const double a = 2 * pi / n;
  const MassProperties fine = mass_properties(cylinder_mesh(r, h, n), 1.0);
  const double mass = pi * r * r * 2 * h;
  EXPECT_NEAR(fine.inertia(2, 2) / (mass * r * r / 2), 1, a * a);
  EXPECT_NEAR(fine.inertia(0, 0) / (mass * (3 * r * r + 4 * h * h) / 12), 1, a * a);
}

TEST(MassProperties, SphereMeshesConvergeToTheSphereAtSecondOrder) {
  // an inscribed polyhedron's volume and moment err by O(edge^2); each subdivision halves the edge
  const double r = 0.7;
  const double volume = 4 * pi * r * r * r / 3;
  std::vector<double> edge, volume_error, moment_error;
  for (int s = 1; s <= 5; ++s) {
    const TriangleMesh mesh = sphere_mesh(r, s);
    const MassProperties m = mass_properties(mesh, 1.0);
    edge.push_back(std::pow(0.5, s));
    volume_error.push_back(std::abs(m.volume / volume - 1));
    // every diagonal entry 2/5 m r^2 of the exact sphere's mass, products zero by symmetry
    moment_error.push_back(std::abs(m.inertia.trace() / 3 / (0.4 * volume * r * r) - 1));
    EXPECT_LT(std::abs(m.inertia(0, 1)) + std::abs(m.inertia(1, 2)) + std::abs(m.inertia(0, 2)), 1e-12 * m.inertia(0, 0));
  }
  const double volume_order = loglog_slope(edge, volume_error), moment_order = loglog_slope(edge, moment_error);
  std::cout << "sphere meshes: volume error " << volume_error.back() << ", moment error " << moment_error.back()
            << " at 20480 triangles; orders " << volume_order << ", " << moment_order << '\n';
  EXPECT_NEAR(volume_order, 2, tolerance::order_band);
  EXPECT_NEAR(moment_order, 2, tolerance::order_band);
}

TEST(MassProperties, OffCentreRotatedBodyHasTheRotatedTensorAndTheParallelAxisTheoremHolds) {
  const Eigen::Vector3d h(0.2, 0.5, 1.0);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  auto placed = [&](const Eigen::Vector3d& centre) {
    TriangleMesh mesh = box_mesh(h);
    for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) mesh.vertices.row(v) = (R * mesh.vertices.row(v).transpose() + centre).transpose();
    return mesh;
  };
  const Eigen::Vector3d c1(3, -1, 2), c2(-1, 4, 0.5);
  const MassProperties box = mass_properties(box_mesh(h), 1.0), one = mass_properties(placed(c1), 1.0);
  EXPECT_LT((one.center - c1).norm(), tolerance::mass_properties_roundoff * c1.norm());
  EXPECT_LT(relative(one.inertia, R * box.inertia * R.transpose()), tolerance::mass_properties_roundoff);
  EXPECT_GT(std::abs(one.inertia(0, 1)), 1e-3 * one.inertia(0, 0)) << "products of inertia are present";
  // two such boxes as one mesh: about their common centre each contributes its own tensor moved by Steiner
  TriangleMesh pair = placed(c1);
  const TriangleMesh second = placed(c2);
  const auto v = pair.vertices.rows(), f = pair.faces.rows();
  pair.vertices.conservativeResize(2 * v, 3);
  pair.faces.conservativeResize(2 * f, 3);
  pair.vertices.bottomRows(v) = second.vertices;
  pair.faces.bottomRows(f) = second.faces.array() + static_cast<int>(v);
  const MassProperties both = mass_properties(pair, 1.0);
  const Eigen::Vector3d centre = (c1 + c2) / 2;
  const Eigen::Matrix3d steiner = shifted_inertia(one.inertia, one.mass, c1 - centre) + shifted_inertia(one.inertia, one.mass, c2 - centre);
  EXPECT_LT((both.center - centre).norm(), tolerance::mass_properties_roundoff * centre.norm());
  EXPECT_LT(relative(both.inertia, steiner), tolerance::mass_properties_roundoff * 100) << "cancellation in the shift: |c|^2 m >> I";
  // and the principal frame takes the tensor back to the box's moments
  const PrincipalFrame frame = principal_frame(one.inertia);
  Eigen::Vector3d sorted = box.inertia.diagonal();
  std::sort(sorted.begin(), sorted.end());
  EXPECT_LT((frame.moments - sorted).cwiseAbs().maxCoeff(), tolerance::mass_properties_roundoff * sorted.maxCoeff());
  EXPECT_NEAR(frame.axes.determinant(), 1, 1e-12);
  EXPECT_LT(relative(frame.axes * frame.moments.asDiagonal() * frame.axes.transpose(), one.inertia), tolerance::mass_properties_roundoff);
}

TEST(MassProperties, MeshesAndTensorsWithoutAMassAreRefusedByName) {
  TriangleMesh open = box_mesh(Eigen::Vector3d::Ones());
  open.faces.conservativeResize(11, 3);
  EXPECT_THROW(
      try { mass_properties(open, 1.0); } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("not closed"), std::string::npos) << e.what();
        throw;
      },
      std::invalid_argument);
  TriangleMesh inside_out = box_mesh(Eigen::Vector3d::Ones());
  inside_out.faces.col(1).swap(inside_out.faces.col(2));
  EXPECT_THROW(
      try { mass_properties(inside_out, 1.0); } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("inside out"), std::string::npos) << e.what();
        throw;
      },
      std::invalid_argument);
  EXPECT_THROW(mass_properties(box_mesh(Eigen::Vector3d::Ones()), 0.0), std::invalid_argument);
  EXPECT_THROW(principal_frame(Eigen::Vector3d(1, 1, -1).asDiagonal()), std::invalid_argument);
  EXPECT_THROW(principal_frame(Eigen::Vector3d(1, 1, 3).asDiagonal()), std::invalid_argument) << "I1 + I2 < I3";
  Eigen::Matrix3d skew = Eigen::Matrix3d::Identity();
  skew(0, 1) = 0.1;
  EXPECT_THROW(principal_frame(skew), std::invalid_argument);
}

}  // namespace
}  // namespace stepwise
