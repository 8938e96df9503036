#include "membrane.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <map>

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

// the change of Ds when coordinate c of corner j moves by one (x0 moves both edges back)
Eigen::Matrix<double, 3, 2> edge_change(int j, int c) {
  Eigen::Matrix<double, 3, 2> dDs = Eigen::Matrix<double, 3, 2>::Zero();
  if (j == 0)
    dDs.row(c).setConstant(-1);
  else
    dDs(c, j - 1) = 1;
  return dDs;
}

Eigen::Matrix2d symmetric_product(const Eigen::Matrix<double, 3, 2>& a, const Eigen::Matrix<double, 3, 2>& b) {
  return (a.transpose() * b + b.transpose() * a) / 2;
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
      const Eigen::Matrix<double, 3, 2> dF = edge_change(j, c) * e.rest_inverse;
      const Eigen::Matrix2d dE = symmetric_product(dF, F);
      const Eigen::Matrix<double, 3, 2> dP = dF * S + F * membrane_stress(m, dE);
      H.col(3 * j + c) = corner_gradient(volume * dP * e.rest_inverse.transpose());
    }
  if (!definite) return -H;
  const Eigen::SelfAdjointEigenSolver<Matrix9d> eigen((H + H.transpose()) / 2);
  const Vector9d clamped = eigen.eigenvalues().cwiseMax(0.0);
  return -(eigen.eigenvectors() * clamped.asDiagonal() * eigen.eigenvectors().transpose());
}

Vector9d membrane_damping_force(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, const Corners3& v, double beta) {
  const Eigen::Matrix<double, 3, 2> F = deformation_gradient(e, x), Fdot = edges(v) * e.rest_inverse;
  const Eigen::Matrix<double, 3, 2> P = F * (beta * membrane_stress(m, symmetric_product(F, Fdot)));
  return -corner_gradient(e.area * m.thickness * P * e.rest_inverse.transpose());
}

Matrix9d membrane_damping_velocity_jacobian(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, double beta) {
  const Eigen::Matrix<double, 3, 2> F = deformation_gradient(e, x);
  Matrix9d J;
  for (int j = 0; j < 3; ++j)
    for (int c = 0; c < 3; ++c) {
      const Eigen::Matrix<double, 3, 2> dFdot = edge_change(j, c) * e.rest_inverse;
      const Eigen::Matrix<double, 3, 2> dP = F * (beta * membrane_stress(m, symmetric_product(F, dFdot)));
      J.col(3 * j + c) = -corner_gradient(e.area * m.thickness * dP * e.rest_inverse.transpose());
    }
  return J;
}

Matrix9d membrane_damping_position_jacobian(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, const Corners3& v, double beta) {
  const Eigen::Matrix<double, 3, 2> F = deformation_gradient(e, x), Fdot = edges(v) * e.rest_inverse;
  const Eigen::Matrix2d S = beta * membrane_stress(m, symmetric_product(F, Fdot));
  Matrix9d J;
  for (int j = 0; j < 3; ++j)
    for (int c = 0; c < 3; ++c) {
      const Eigen::Matrix<double, 3, 2> dF = edge_change(j, c) * e.rest_inverse;
      const Eigen::Matrix<double, 3, 2> dP = dF * S + F * (beta * membrane_stress(m, symmetric_product(dF, Fdot)));
      J.col(3 * j + c) = -corner_gradient(e.area * m.thickness * dP * e.rest_inverse.transpose());
    }
  return J;
}

namespace {

// the cotangent of the angle at p in the triangle (p, q, r)
double cot_at(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
  const Eigen::Vector3d u = q - p, w = r - p;
  return u.dot(w) / u.cross(w).norm();
}

}  // namespace

std::vector<BendingStencil> bending_stencils(std::span<const std::array<int, 3>> triangles, std::span<const Eigen::Vector3d> rest,
                                             const std::vector<bool>& interior) {
  // each vertex's neighbours with their cotangent weights, and its barycentric area
  std::vector<std::map<int, double>> weights(rest.size());
  std::vector<double> area(rest.size(), 0.0);
  for (const auto& t : triangles) {
    const double a = (rest[t[1]] - rest[t[0]]).cross(rest[t[2]] - rest[t[0]]).norm() / 2;
    for (int i = 0; i < 3; ++i) {
      const int p = t[i], q = t[(i + 1) % 3], o = t[(i + 2) % 3];
      const double w = cot_at(rest[o], rest[p], rest[q]) / 2;  // the edge (p, q)'s share from this triangle
      weights[p][q] += w;
      weights[q][p] += w;
      area[p] += a / 3;
    }
  }
  std::vector<BendingStencil> stencils;
  for (size_t v = 0; v < rest.size(); ++v) {
    if (!interior[v]) continue;
    BendingStencil s;
    s.node.push_back(static_cast<int>(v));
    Eigen::VectorXd c(static_cast<Eigen::Index>(weights[v].size() + 1));
    c[0] = 0;
    Eigen::Index k = 1;
    for (const auto& [j, w] : weights[v]) {
      s.node.push_back(j);
      c[k++] = w;
      c[0] -= w;
    }
    s.Q = c * c.transpose() / area[v];
    stencils.push_back(std::move(s));
  }
  return stencils;
}

double bending_energy(double D, const BendingStencil& s, std::span<const Eigen::Vector3d> x) {
  double w = 0;
  for (size_t i = 0; i < s.node.size(); ++i)
    for (size_t j = 0; j < s.node.size(); ++j) w += s.Q(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) * x[i].dot(x[j]);
  return D / 2 * w;
}

std::vector<Eigen::Vector3d> bending_force(double D, const BendingStencil& s, std::span<const Eigen::Vector3d> x) {
  std::vector<Eigen::Vector3d> f(s.node.size(), Eigen::Vector3d::Zero());
  for (size_t i = 0; i < s.node.size(); ++i) {
    for (size_t j = 0; j < s.node.size(); ++j) f[i] += s.Q(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) * x[j];
    f[i] *= -D;
  }
  return f;
}

}  // namespace stepwise
