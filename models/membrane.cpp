#include "membrane.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace stepwise {

MembraneMaterial::MembraneMaterial(double young_, double poisson_, double thickness_)
    : young(young_),
      poisson(poisson_),
      thickness(thickness_),
      mu(young_ / (2 * (1 + poisson_))),
      lambda(young_ * poisson_ / (1 - poisson_ * poisson_)),
      bending(young_ * thickness_ * thickness_ * thickness_ / (12 * (1 - poisson_ * poisson_))) {}

MembraneElement make_membrane_element(std::array<int, 3> node, const Eigen::Vector2d& X0, const Eigen::Vector2d& X1, const Eigen::Vector2d& X2) {
  Eigen::Matrix2d Dm;
  Dm << X1 - X0, X2 - X0;
  return {node, Dm.inverse(), std::abs(Dm.determinant()) / 2};
}

namespace {

// Ds = [x1 - x0, x2 - x0]
Eigen::Matrix<double, 3, 2> edges(const Corners3& x) {
  Eigen::Matrix<double, 3, 2> Ds;
  Ds << x[1] - x[0], x[2] - x[0];
  return Ds;
}

// dW/dx of the three corners from G = dW/dDs (3 x 2): x1's is G's first column,
// x2's its second, x0's minus both
Vector9d corner_gradient(const Eigen::Matrix<double, 3, 2>& G) {
  Vector9d g;
  g << -G.col(0) - G.col(1), G.col(0), G.col(1);
  return g;
}

}  // namespace

Eigen::Matrix<double, 3, 2> deformation_gradient(const MembraneElement& e, const Corners3& x) { return edges(x) * e.rest_inverse; }

Eigen::Matrix2d green_strain(const Eigen::Matrix<double, 3, 2>& F) { return (F.transpose() * F - Eigen::Matrix2d::Identity()) / 2; }

Eigen::Matrix2d membrane_stress(const MembraneMaterial& m, const Eigen::Matrix2d& E) {
  return 2 * m.mu * E + m.lambda * E.trace() * Eigen::Matrix2d::Identity();
}

double membrane_energy(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x) {
  const Eigen::Matrix2d E = green_strain(deformation_gradient(e, x));
  const double psi = m.mu * E.squaredNorm() + m.lambda / 2 * E.trace() * E.trace();
  return e.area * m.thickness * psi;
}

Vector9d membrane_force(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x) {
  const Eigen::Matrix<double, 3, 2> F = deformation_gradient(e, x);
  const Eigen::Matrix<double, 3, 2> P = F * membrane_stress(m, green_strain(F));
  return -corner_gradient(e.area * m.thickness * P * e.rest_inverse.transpose());
}

Matrix9d membrane_force_jacobian(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, bool definite) {
  const Eigen::Matrix<double, 3, 2> F = deformation_gradient(e, x);
  const Eigen::Matrix2d S = membrane_stress(m, green_strain(F));
  const double volume = e.area * m.thickness;
  Matrix9d H;  // d^2 W / dx^2, a column per coordinate
  for (int j = 0; j < 3; ++j)
    for (int c = 0; c < 3; ++c) {
      Eigen::Matrix<double, 3, 2> dDs = Eigen::Matrix<double, 3, 2>::Zero();
      if (j == 0)
        dDs.row(c).setConstant(-1);
      else
        dDs(c, j - 1) = 1;
      const Eigen::Matrix<double, 3, 2> dF = dDs * e.rest_inverse;
      const Eigen::Matrix2d dE = (dF.transpose() * F + F.transpose() * dF) / 2;
      const Eigen::Matrix<double, 3, 2> dP = dF * S + F * membrane_stress(m, dE);
      H.col(3 * j + c) = corner_gradient(volume * dP * e.rest_inverse.transpose());
    }
  if (!definite) return -H;
  const Eigen::SelfAdjointEigenSolver<Matrix9d> eigen((H + H.transpose()) / 2);
  const Vector9d clamped = eigen.eigenvalues().cwiseMax(0.0);
  return -(eigen.eigenvectors() * clamped.asDiagonal() * eigen.eigenvectors().transpose());
}

namespace {

// the cotangent of the angle at p in the triangle (p, q, r)
double cot_at(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
  const Eigen::Vector3d u = q - p, w = r - p;
  return u.dot(w) / u.cross(w).norm();
}

}  // namespace

BendingStencil make_bending_stencil(std::array<int, 4> node, const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                                    const Eigen::Vector3d& x3) {
  const double a0A = cot_at(x0, x1, x2), a1A = cot_at(x1, x2, x0), a0B = cot_at(x0, x1, x3), a1B = cot_at(x1, x3, x0);
  const Eigen::Vector4d K(-(a1A + a1B), -(a0A + a0B), a0A + a1A, a0B + a1B);
  const double areas = ((x1 - x0).cross(x2 - x0).norm() + (x1 - x0).cross(x3 - x0).norm()) / 2;
  return {node, 3 / areas * K * K.transpose()};
}

double bending_energy(double D, const BendingStencil& s, const std::array<Eigen::Vector3d, 4>& x) {
  double w = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) w += s.Q(i, j) * x[static_cast<size_t>(i)].dot(x[static_cast<size_t>(j)]);
  return D / 2 * w;
}

std::array<Eigen::Vector3d, 4> bending_force(double D, const BendingStencil& s, const std::array<Eigen::Vector3d, 4>& x) {
  std::array<Eigen::Vector3d, 4> f;
  for (int i = 0; i < 4; ++i) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int j = 0; j < 4; ++j) sum += s.Q(i, j) * x[static_cast<size_t>(j)];
    f[static_cast<size_t>(i)] = -D * sum;
  }
  return f;
}

}  // namespace stepwise
