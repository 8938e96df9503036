// The linear system of every Newton iteration of an implicit step: (I - h J) d = r, J = df/dy.
//
// Dense Eigen LU for small systems now; a sparse CHOLMOD implementation plugs in behind the same
// interface for the SPD mass-spring systems (the cloth issue).
#pragma once

#include <Eigen/Dense>

#include <memory>

namespace stepwise {

class CountedSystem;

class NewtonMatrix {
 public:
  virtual ~NewtonMatrix() = default;
  // evaluate J at (t, y) and factorise I - h J; false when the matrix is singular
  virtual bool factor(double t, const Eigen::VectorXd& y, double h) = 0;
  // d = (I - h J)^-1 r with the last factorisation
  virtual void solve(const Eigen::VectorXd& r, Eigen::VectorXd& d) = 0;
};

// dense LU with partial pivoting; J analytic where the system has one, else central differences
std::unique_ptr<NewtonMatrix> make_dense_newton_matrix(const CountedSystem& system);

}  // namespace stepwise
