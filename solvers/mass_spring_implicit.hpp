// Implicit Euler for mass-spring systems (OdeSystem::mass_spring) in Baraff & Witkin's form (SIGGRAPH 1998,
// "Large steps in cloth simulation", eq. 15-16): with K = df/dx and D = df/dv at the step's start (the
// symmetric definite approximation the system gives), one linear solve per step,
//   (M - h D - h^2 K) dv = h (f0 + h K v0),   v1 = v0 + dv,   x1 = x0 + h v1,
// the backward Euler step linearised once. With `newton`, the nonlinear backward Euler equations
//   R(v1) = M (v1 - v0) - h f(x0 + h v1, v1) = 0
// are iterated to |R| <= newton_residual (|M v1| + h |f|), each iteration solving the same kind of matrix at the
// latest iterate (a quasi-Newton iteration: the matrix is the definite approximation, the residual exact).
//
// The matrix is symmetric positive definite and its pattern never changes: CHOLMOD analyses it once (AMD or
// METIS, whichever factor is cheaper) and factorises it with the analysis kept. How each solve is done:
//  - refactor: a numeric factorisation every solve, then two triangular solves (the direct way);
//  - kept_factor: conjugate gradients on the new matrix, preconditioned by the factor of an earlier one,
//    to a relative residual |b - A dv| <= cg_residual |b|; the factor is refreshed when an iteration count
//    climbs past refresh_iterations (the matrix has drifted from the factored one), and at once when the
//    iteration fails to converge in cg_max_iterations. A cloth's matrix changes slowly from step to step,
//    so one factor serves many steps at a few triangular solves each.
#pragma once

#include "fixed_step.hpp"
#include "sparse_cholesky.hpp"

#include <Eigen/SparseCore>

#include <memory>

namespace stepwise {

enum class LinearSolve { refactor, kept_factor };

struct MassSpringImplicitOptions {
  bool newton = false;
  LinearSolve solve = LinearSolve::kept_factor;
  Ordering ordering = Ordering::cheaper;
  bool definite = true;           // the definite approximation of K; false: the exact one, which a compressed
                                  // spring makes indefinite (the factorisation then fails, reported)
  double cg_residual = 1e-8;      // relative residual of the kept-factor conjugate gradients
  int cg_max_iterations = 200;
  int refresh_iterations = 8;     // refactor when a solve took more iterations than this
  double newton_residual = 1e-10;
  int newton_max_iterations = 20;
};

// the linear system of one step: A = M - h D - h^2 K and b = h (f0 + h K v0) at (t, y), for a mass-spring
// system; the pattern of A is the same at every call
class BaraffWitkinSystem {
 public:
  BaraffWitkinSystem(const OdeSystem& system, bool definite);
  // the matrix at (t, x, v) and f(t, x, v) there (f = M a)
  void assemble_matrix(double t, const Eigen::VectorXd& y, double h);
  // b = h (f0 + h K v0), with the K and f0 of the last assemble_matrix at y
  void assemble_rhs(const Eigen::VectorXd& y, double h);
  const Eigen::SparseMatrix<double>& matrix() const { return a_; }
  const Eigen::VectorXd& rhs() const { return b_; }
  const Eigen::VectorXd& force() const { return f_; }  // f at the last assembly
  const Eigen::VectorXd& mass() const { return m_; }   // per coordinate

 private:
  const OdeSystem& system_;
  bool definite_;
  Eigen::VectorXd m_, f_, b_;
  Eigen::SparseMatrix<double> k_, d_, a_;
};

std::unique_ptr<FixedStepper> make_mass_spring_implicit(const CountedSystem& system, const MassSpringImplicitOptions& options);

}  // namespace stepwise
