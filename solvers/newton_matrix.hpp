// The linear system of every Newton iteration of an implicit step: (I - h J) d = r, J = df/dy: dense Eigen LU,
// or UMFPACK's sparse LU on a large system's sparse Jacobian (sparse_newton_matrix.cpp).
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

// sparse LU (UMFPACK) on the system's sparse Jacobian (which it must have), its pattern analysed once
std::unique_ptr<NewtonMatrix> make_sparse_newton_matrix(const CountedSystem& system);

// a system this large with a sparse Jacobian is factorised sparse: a dense LU's n^3/3 passes the sparse one's
// analysis and fill well before (the standing wave's 578 unknowns: 64 MFLOP a step dense)
inline constexpr int sparse_newton_from = 64;

// the sparse matrix from sparse_newton_from unknowns on where the system has a sparse Jacobian, else the dense one
std::unique_ptr<NewtonMatrix> make_newton_matrix(const CountedSystem& system);

}  // namespace stepwise
