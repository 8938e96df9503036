#include "mass_properties.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <stdexcept>

namespace stepwise {
namespace {

// Eberly's subexpressions of one coordinate w of a triangle's three vertices
struct Sub {
  double f1, f2, f3, g0, g1, g2;
};
Sub subexpressions(double w0, double w1, double w2) {
  const double t0 = w0 + w1, t1 = w0 * w0, t2 = t1 + w1 * t0;
  Sub s;
  s.f1 = t0 + w2;
  s.f2 = t2 + w2 * s.f1;
  s.f3 = w0 * t1 + w1 * t2 + w2 * s.f2;
  s.g0 = s.f2 + w0 * (s.f1 + w0);
  s.g1 = s.f2 + w1 * (s.f1 + w1);
  s.g2 = s.f2 + w2 * (s.f1 + w2);
  return s;
}

}  // namespace

MassProperties mass_properties(const TriangleMesh& mesh, double density) {
  if (!(density > 0) || !std::isfinite(density)) throw std::invalid_argument(fmt::format("density {} is not positive", density));
  validate_closed(mesh);
  // integrals of 1, x, y, z, x^2, y^2, z^2, xy, yz, zx over the solid, before their constant factors
  std::array<double, 10> in{};
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    const Eigen::Vector3d p0 = mesh.vertices.row(mesh.faces(f, 0)).transpose(), p1 = mesh.vertices.row(mesh.faces(f, 1)).transpose(),
                          p2 = mesh.vertices.row(mesh.faces(f, 2)).transpose();
    const Eigen::Vector3d d = (p1 - p0).cross(p2 - p0);
    const Sub x = subexpressions(p0.x(), p1.x(), p2.x()), y = subexpressions(p0.y(), p1.y(), p2.y()),
              z = subexpressions(p0.z(), p1.z(), p2.z());
    in[0] += d.x() * x.f1;
    in[1] += d.x() * x.f2;
    in[2] += d.y() * y.f2;
    in[3] += d.z() * z.f2;
    in[4] += d.x() * x.f3;
    in[5] += d.y() * y.f3;
    in[6] += d.z() * z.f3;
    in[7] += d.x() * (p0.y() * x.g0 + p1.y() * x.g1 + p2.y() * x.g2);
    in[8] += d.y() * (p0.z() * y.g0 + p1.z() * y.g1 + p2.z() * y.g2);
    in[9] += d.z() * (p0.x() * z.g0 + p1.x() * z.g1 + p2.x() * z.g2);
  }
  constexpr std::array<double, 10> factor{1.0 / 6, 1.0 / 24, 1.0 / 24, 1.0 / 24, 1.0 / 60, 1.0 / 60, 1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 120};
  for (size_t k = 0; k < in.size(); ++k) in[k] *= factor[k];
  const Aabb box = bounding_box(mesh);
  const double scale = (box.hi - box.lo).prod();
  if (!(std::abs(in[0]) > 1e-12 * scale)) throw std::invalid_argument("mesh encloses no volume");
  if (in[0] < 0) throw std::invalid_argument("mesh is inside out: its faces are clockwise seen from outside (negative volume)");
  MassProperties m;
  m.volume = in[0];
  m.mass = density * in[0];
  m.center = Eigen::Vector3d(in[1], in[2], in[3]) / in[0];
  const Eigen::Vector3d& c = m.center;
  // second moments about the origin, then moved to the centre of mass
  Eigen::Matrix3d origin;
  origin << in[5] + in[6], -in[7], -in[9],  //
      -in[7], in[4] + in[6], -in[8],         //
      -in[9], -in[8], in[4] + in[5];
  m.inertia = density * origin - shifted_inertia(Eigen::Matrix3d::Zero(), m.mass, c);
  return m;
}

Eigen::Matrix3d shifted_inertia(const Eigen::Matrix3d& inertia, double mass, const Eigen::Vector3d& offset) {
  return inertia + mass * (offset.squaredNorm() * Eigen::Matrix3d::Identity() - offset * offset.transpose());
}

int moment_beyond_the_others(const Eigen::Vector3d& moments) {
  for (int k = 0; k < 3; ++k)
    if (moments[k] > (moments.sum() - moments[k]) * (1 + 1e-12)) return k;
  return -1;
}

PrincipalFrame principal_frame(const Eigen::Matrix3d& inertia) {
  const double size = inertia.cwiseAbs().maxCoeff();
  if (!inertia.allFinite() || !(size > 0)) throw std::invalid_argument("inertia tensor is zero or not finite");
  if ((inertia - inertia.transpose()).cwiseAbs().maxCoeff() > 1e-12 * size) throw std::invalid_argument("inertia tensor is not symmetric");
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(inertia);  // eigenvalues ascending
  PrincipalFrame frame{eigen.eigenvalues(), eigen.eigenvectors()};
  if (!(frame.moments[0] > 1e-12 * size)) throw std::invalid_argument(fmt::format("inertia tensor is not positive definite (smallest moment {:g})", frame.moments[0]));
  if (moment_beyond_the_others(frame.moments) >= 0)
    throw std::invalid_argument(fmt::format("principal moments {:g}, {:g}, {:g} break I1 + I2 >= I3: no body has them", frame.moments[0],
                                            frame.moments[1], frame.moments[2]));
  if (frame.axes.determinant() < 0) frame.axes.col(2) *= -1;
  return frame;
}

}  // namespace stepwise
