#include "membrane.hpp"

#include <algorithm>
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

namespace {

// the stress's tension alone: S with its negative principal stresses set to zero (a 2 x 2 symmetric's eigensystem
// in closed form)
Eigen::Matrix2d tension(const Eigen::Matrix2d& S) {
  const double mean = (S(0, 0) + S(1, 1)) / 2, half = std::hypot((S(0, 0) - S(1, 1)) / 2, S(0, 1));
  const double high = mean + half, low = mean - half;
  if (low >= 0) return S;
  if (high <= 0) return Eigen::Matrix2d::Zero();
  // S = high q q^T + low (I - q q^T): its tension high q q^T = high (S - low I) / (high - low)
  return high / (high - low) * (S - low * Eigen::Matrix2d::Identity());
}

// d^2 W / dx_i dx_j, the Hessian's 3 x 3 block for corners i and j, in closed form. Corner i moving by d changes F by
// d w_i^T (w_1, w_2 the rows of Dm^-1, w_0 = -w_1 - w_2), and E by sym(F^T d w_i^T); with u_i = F w_i the second
// variation dF : dF S' + dE : C : dE gives
//     A h [ (w_i^T S' w_j) I + mu (w_i . w_j) F F^T + mu u_j u_i^T + lambda u_i u_j^T ],
// its first term the geometric stiffness, S' the stress S (exact) or its tension alone (definite), the others the
// material's, semidefinite (C's 2 mu and mu + lambda = Y / (2 (1 - nu)) are positive)
class HessianBlocks {
 public:
  HessianBlocks(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, bool definite)
      : F_(deformation_gradient(e, x)), S_(membrane_stress(m, green_strain(F_))), scale_(e.area * m.thickness), mu_(m.mu), lambda_(m.lambda) {
    geometric_ = definite ? tension(S_) : S_;
    w_.col(1) = e.rest_inverse.row(0).transpose();
    w_.col(2) = e.rest_inverse.row(1).transpose();
    w_.col(0) = -w_.col(1) - w_.col(2);
    u_ = F_ * w_;
    stretch_ = F_ * F_.transpose();
  }
  Eigen::Matrix3d operator()(int i, int j) const {
    Eigen::Matrix3d b = (mu_ * w_.col(i).dot(w_.col(j))) * stretch_ + mu_ * u_.col(j) * u_.col(i).transpose() + lambda_ * u_.col(i) * u_.col(j).transpose();
    b.diagonal().array() += w_.col(i).dot(geometric_ * w_.col(j));
    return scale_ * b;
  }
  const Eigen::Matrix<double, 3, 2>& F() const { return F_; }
  const Eigen::Matrix2d& S() const { return S_; }

 private:
  Eigen::Matrix<double, 3, 2> F_;
  Eigen::Matrix2d S_, geometric_;
  double scale_, mu_, lambda_;
  Eigen::Matrix<double, 2, 3> w_;
  Eigen::Matrix3d u_, stretch_;
};

}  // namespace

Matrix9d membrane_force_jacobian(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, bool definite) {
  const HessianBlocks H(m, e, x, definite);
  Matrix9d J;
  for (int i = 0; i < 3; ++i) {
    J.block<3, 3>(3 * i, 3 * i) = -H(i, i);
    for (int j = i + 1; j < 3; ++j) {
      J.block<3, 3>(3 * i, 3 * j) = -H(i, j);
      J.block<3, 3>(3 * j, 3 * i) = J.block<3, 3>(3 * i, 3 * j).transpose();
    }
  }
  return J;
}

void membrane_corner(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, int j, bool definite, Eigen::Vector3d& force,
                     Eigen::Matrix3d& jacobian) {
  const HessianBlocks H(m, e, x, definite);
  force = -corner_gradient(e.area * m.thickness * H.F() * H.S() * e.rest_inverse.transpose()).segment<3>(3 * j);
  jacobian = -H(j, j);
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

// a stencil's coefficients: grid node -> its weight in one finite difference
using Difference = std::map<int, double>;

// the second difference along a line of `count` nodes at position i (central inside, the nearest three on an edge), the
// grid node of position j being node(j); empty where the line has fewer than three nodes
template <class Node>
Difference second_difference(int i, int count, double spacing, Node node) {
  if (count < 3) return {};
  const int centre = std::clamp(i, 1, count - 2);
  return {{node(centre - 1), 1 / (spacing * spacing)}, {node(centre), -2 / (spacing * spacing)}, {node(centre + 1), 1 / (spacing * spacing)}};
}

// sum_t weight_t (c_t . x)^2 as a stencil: the nodes the differences touch and Q = sum_t weight_t c_t c_t^T
BendingStencil quadratic_form(const std::vector<std::pair<double, Difference>>& terms) {
  BendingStencil s;
  std::map<int, Eigen::Index> index;
  for (const auto& [weight, c] : terms)
    for (const auto& [node, coefficient] : c)
      if (index.emplace(node, static_cast<Eigen::Index>(s.node.size())).second) s.node.push_back(node);
  s.Q = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(s.node.size()), static_cast<Eigen::Index>(s.node.size()));
  for (const auto& [weight, c] : terms) {
    Eigen::VectorXd v = Eigen::VectorXd::Zero(s.Q.rows());
    for (const auto& [node, coefficient] : c) v[index.at(node)] += coefficient;
    s.Q += weight * v * v.transpose();
  }
  return s;
}

Difference sum(Difference a, const Difference& b) {
  for (const auto& [node, coefficient] : b) a[node] += coefficient;
  return a;
}

}  // namespace

std::vector<BendingStencil> plate_bending_stencils(int rows, int columns, double dx, double dy, double nu) {
  const auto trapezoid = [](int i, int count, double spacing) { return i == 0 || i == count - 1 ? spacing / 2 : spacing; };
  std::vector<BendingStencil> stencils;
  // each node: nu |x_XX + x_YY|^2 + (1 - nu) (|x_XX|^2 + |x_YY|^2), times its area
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      const Difference xx = second_difference(c, columns, dx, [&](int j) { return r * columns + j; });
      const Difference yy = second_difference(r, rows, dy, [&](int j) { return j * columns + c; });
      const double area = trapezoid(c, columns, dx) * trapezoid(r, rows, dy);
      stencils.push_back(quadratic_form({{nu * area, sum(xx, yy)}, {(1 - nu) * area, xx}, {(1 - nu) * area, yy}}));
    }
  // each cell: 2 (1 - nu) |x_XY|^2 times its area
  for (int r = 0; r + 1 < rows; ++r)
    for (int c = 0; c + 1 < columns; ++c) {
      const int k = r * columns + c;
      const double w = 1 / (dx * dy);
      const Difference xy{{k, w}, {k + 1, -w}, {k + columns, -w}, {k + columns + 1, w}};
      stencils.push_back(quadratic_form({{2 * (1 - nu) * dx * dy, xy}}));
    }
  return stencils;
}

double bending_energy(double D, const BendingStencil& s, std::span<const Eigen::Vector3d> x) {
  double w = 0;
  for (size_t i = 0; i < s.node.size(); ++i)
    for (size_t j = 0; j < s.node.size(); ++j) w += s.Q(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) * x[i].dot(x[j]);
  return D / 2 * w;
}

Eigen::Vector3d bending_force_on(double D, const BendingStencil& s, std::span<const Eigen::Vector3d> x, size_t i) {
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  for (size_t j = 0; j < s.node.size(); ++j) f += s.Q(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) * x[j];
  return -D * f;
}

}  // namespace stepwise
