// Implicit Euler for mass-spring systems (MassSpringView, solvers/capabilities/mass_spring.hpp) in Baraff & Witkin's form (SIGGRAPH 1998,
// "Large steps in cloth simulation", eq. 15-16): with K = df/dx and D = df/dv at the step's start (the
// symmetric definite approximation the system gives), one linear solve per step,
//   (M - h D - h^2 K) dv = h (f0 + h K v0),   v1 = v0 + dv,   x1 = x0 + h v1,
// the backward Euler step linearised once. With `newton`, backward Euler itself: the step's incremental potential
// G (incremental_potential.hpp: the elastic forces implicit, the others at the step's start) minimised by Newton
// from the linearised step's answer (inexact Newton on G's exact Hessian, modified where that is not positive
// definite: incremental_potential.hpp), a line search on G, to a step that moves no node faster than the velocity
// tolerance. The linearised step is then only Newton's first guess, solved inexactly (kept_factor): CG preconditioned
// by Newton's last factor to a loose relative residual (mass_spring_implicit.cpp, guess_residual). (A Newton on the
// residual's norm with GMRES on the exact Jacobian was measured before it: it stalls where a buckling sheet makes the
// energy non-convex, at points that are no root, and failed the flag at every step from 1/120 s up.)
//
// The matrix is symmetric positive definite and its pattern never changes: CHOLMOD analyses it once (AMD or
// METIS, whichever factor is cheaper) and factorises it with the analysis kept. How each solve is done:
//  - refactor: a numeric factorisation every solve, then two triangular solves (the direct way);
//  - kept_factor: conjugate gradients on the new matrix, preconditioned by the factor of an earlier one,
//    to a relative residual |b - A dv| <= cg_residual |b|, started from the last step's dv, for at most as
//    many iterations as a refactorisation costs (both timed as they run: the ratio is 1.4 per flop at
//    32 x 32 and 8 at 64 x 64, so no flop count predicts it); past that the factor is refreshed and the
//    solve done with it. A fresh factor's first reuse is probed for 3 iterations, whose convergence rate
//    predicts whether the limit will do; a factor that would not pay is given up there. The timing
//    decides only when to refactor: every answer meets the same residual, but two runs may differ below it. Where the matrix changes slowly (a hanging sheet) one factor serves many steps at a
//    few triangular solves each; where it does not (a flag flapping in a gusting wind: M is small against
//    h^2 K, so a spring turning by h |dv| / l changes the matrix by O(M) in its soft directions) the
//    stepper finds the kept factor never pays and refactorises, trying again after runs that double.
#pragma once

#include <stepwise/solvers/fixed_step.hpp>
#include <stepwise/solvers/incremental_potential.hpp>
#include <stepwise/solvers/run_support.hpp>
#include <stepwise/solvers/sparse_cholesky.hpp>

#include <Eigen/SparseCore>

#include <memory>

namespace stepwise {

enum class LinearSolve { refactor, kept_factor };

struct MassSpringImplicitOptions {
  bool newton = false;
  bool exact_newton = false;      // every Newton direction from a fresh factor (incremental_potential.hpp), not CG on one
  LinearSolve solve = LinearSolve::kept_factor;
  Ordering ordering = Ordering::cheaper;
  bool definite = true;           // the definite approximation of K; false: the exact one, which a compressed
                                  // spring makes indefinite (the factorisation then fails, reported)
  double cg_residual = 1e-8;      // relative residual of the kept-factor conjugate gradients
  int cg_max_iterations = 200;
};

// the linear system of one step: A = M - h D - h^2 K and b = h (f0 + h K v0) at (t, y), for a mass-spring
// system; the pattern of A is the same at every call
class BaraffWitkinSystem {
 public:
  BaraffWitkinSystem(const CountedSystem& system, bool definite);
  // the matrix at (t, x, v) and f(t, x, v) there (f = M a)
  void assemble_matrix(double t, const Eigen::VectorXd& y, double h);
  // b = h (f0 + h K v0), with the K and f0 of the last assemble_matrix at y
  void assemble_rhs(const Eigen::VectorXd& y, double h);
  // f(t, x, v) alone
  void assemble_force(double t, const Eigen::VectorXd& y);
  // the backward Euler residual's exact Jacobian J = M - h D - h^2 K at (t, x, v), with the model's exact K and
  // D (indefinite where a spring or element is compressed, unsymmetric where the wind turns with the normals)
  void assemble_exact(double t, const Eigen::VectorXd& y, double h);
  const Eigen::SparseMatrix<double>& exact_matrix() const { return j_; }
  const Eigen::SparseMatrix<double>& matrix() const { return a_; }
  const Eigen::VectorXd& rhs() const { return b_; }
  const Eigen::VectorXd& force() const { return f_; }  // f at the last assembly
  const Eigen::SparseMatrix<double>& damping() const { return d_; }  // D = df/dv at the last assemble_matrix
  const Eigen::VectorXd& mass() const { return m_; }   // per coordinate

 private:
  const CountedSystem& system_;
  const MassSpringView& view_;
  bool definite_;
  Eigen::VectorXd m_, f_, b_;
  Eigen::VectorXd scratch_;  // f where the model has no acceleration of its own
  Eigen::SparseMatrix<double> k_, d_, a_, exact_k_, exact_d_, j_;
  StepMatrix step_matrix_, exact_step_matrix_;
};

std::unique_ptr<FixedStepper> make_mass_spring_implicit(const CountedSystem& system, const MassSpringImplicitOptions& options);

// the steppers of implicit-euler (this step on a mass-spring system, dense Newton otherwise) and of
// fast-mass-spring (solvers/methods/), for the benches that step them one at a time
std::unique_ptr<FixedStepper> make_implicit_euler(const CountedSystem& system);
std::unique_ptr<FixedStepper> make_fast_mass_spring(const CountedSystem& system);
constexpr int fast_mass_spring_iterations = 10;  // its local/global iterations a step (Liu et al. 2013, section 4: ten a frame)

}  // namespace stepwise
