// Backward Euler on a mass-spring system (MassSpringView) as the minimisation of one incremental potential
// (Martin, Thomaszewski, Grinspun & Gross 2011; Gast, Schroeder, Stomakhin, Jiang & Teran 2015, "Optimization
// integrator for large time steps"; Kim & Eberle, "Dynamic Deformables", 2022):
//     G(x) = 1/2 (x - xb)^T (M / h^2 - D0 / h) (x - xb) - f0^T x + Psi(x),    xb = x0 + h v0,
// with Psi the elastic potential (springs, or the continuum's membrane and bending), f0 = f(t0, x0, v0) - f_e(x0)
// every other force at the step's start (wind, a pick, gravity, drag, damping: lagged), and D0 = df/dv there
// (symmetric negative semidefinite: the view's definite D; the damping taken implicitly to first order, as
// Baraff & Witkin's step does). Its gradient vanishes exactly where
//     M (v1 - v0) = h (f_e(x1) + f0 + D0 (v1 - v0)),    v1 = (x1 - x0) / h,
// backward Euler's equations with the elastic forces implicit. M / h^2 - D0 / h is positive definite, so G is
// bounded below wherever Psi is, and a descent method on G cannot stall at a point that is no minimum (a Newton
// iteration on the residual's norm can, on a non-convex Psi: a buckling sheet). One definition, shared by every
// solver of it: Newton here (implicit-euler-newton), the linearised step is its first Newton step from xb.
#pragma once

#include <stepwise/solvers/capabilities/mass_spring.hpp>
#include <stepwise/solvers/run_support.hpp>
#include <stepwise/solvers/sparse_cholesky.hpp>

#include <Eigen/SparseCore>

#include <functional>
#include <string>
#include <vector>

namespace stepwise {

// a = M - h D - h^2 K (M diagonal, `mass` a coordinate each): the matrix of every implicit step on a mass-spring
// system (Baraff & Witkin's, backward Euler's Newton, h^2 times the incremental potential's Hessian). The models give
// D and K on one pattern that holds the diagonal, the same at every call (MassSpringView): once a call has seen them
// so, later calls write a's values on that pattern entry by entry, looking only at the sizes (the pattern compared
// at every call was a fifth of the continuum's Hessian assembly); otherwise a sparse expression
class StepMatrix {
 public:
  void operator()(const Eigen::VectorXd& mass, const Eigen::SparseMatrix<double>& d, const Eigen::SparseMatrix<double>& k, double h,
                  Eigen::SparseMatrix<double>& a);

 private:
  bool shared_ = false;                 // D, K and a were seen on one pattern
  std::vector<Eigen::Index> diagonal_;  // where each column's diagonal entry is in it
};

class IncrementalPotential {
 public:
  IncrementalPotential(const CountedSystem& system, const MassSpringView& view);
  // the step from (t0, y0 = (x0, v0)) of length h: xb, f0 and D0 (one evaluation of f, one of its Jacobians)
  void start(double t0, const Eigen::VectorXd& y0, double h);
  // the same from f(t0, y0) (M a) and D0 the caller has evaluated there already (a linearised step's assembly, its D
  // the definite one): no evaluation of f's Jacobians
  void start(double t0, const Eigen::VectorXd& y0, double h, const Eigen::VectorXd& force, const Eigen::SparseMatrix<double>& damping);
  // G(x), and its gradient (dimension nodes x 1)
  double value(const Eigen::VectorXd& x) const;
  // G(x + dx) - G(x), its quadratic and linear parts as differences (G's own terms are of order |f0| |x|, and their
  // round-off would hide the last Newton steps' decrease), the elastic part as Psi's difference
  double change(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const;
  // the same from Psi(x) known, and Psi(x + dx) given back (a line search's accepted trial is its next x)
  double change(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double elastic_at_x, double& elastic_after) const;
  double elastic(const Eigen::VectorXd& x) const;  // Psi(x)
  void gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const;
  // h^2 times G's Hessian, M - h D0 - h^2 K(x): exact (positive definite near a minimum, where Newton then converges
  // quadratically), or (definite) with each spring's or element's Hessian made semidefinite, positive definite
  // everywhere. One evaluation of the elastic Jacobian
  void scaled_hessian(const Eigen::VectorXd& x, bool definite, Eigen::SparseMatrix<double>& a) const;
  // G as a function of node i's position alone, the others held (a per-vertex solver's view, vbd's): its value up to
  // a constant that does not depend on x_i, and with `derivatives` its gradient and 3 x 3 Hessian there (in the plane,
  // z held at zero: the gradient's third entry zero, the Hessian's third row and column the mass term's) (h^-2 times
  // scaled_hessian's diagonal block; definite: each term's block made semidefinite). Touches only node i's terms:
  // its springs or elements, and the rows of D0 at node i
  struct Vertex {
    double value = 0;
    Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
    Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
    // G's terms other than the elastic ones are quadratic in x_i: their gradient and Hessian (with `derivatives`), and
    // the elastic terms' energy
    Eigen::Vector3d quadratic_gradient = Eigen::Vector3d::Zero();
    Eigen::Matrix3d quadratic_hessian = Eigen::Matrix3d::Zero();
    double elastic_energy = 0;
  };
  Vertex vertex(int i, const Eigen::VectorXd& x, bool definite, bool derivatives) const;
  // G's change when node i moves by d from where `at` was evaluated (with derivatives), x holding the node moved: the
  // quadratic terms' change exactly (at's gradient and Hessian along d), the elastic terms' as their energies' difference
  double vertex_change(int i, const Eigen::VectorXd& x, const Vertex& at, const Eigen::Vector3d& d) const;
  double h() const { return h_; }
  int dimension() const { return view_.dimension; }
  const Eigen::VectorXd& inertial() const { return xb_; }  // xb = x0 + h v0
  const Eigen::VectorXd& x0() const { return x0_; }
  const Eigen::VectorXd& mass() const { return m_; }  // each coordinate's lumped mass
  const Eigen::VectorXd& other_forces() const { return f0_; }  // f0
  const Eigen::SparseMatrix<double>& damping() const { return d0_; }  // D0 (definite), on the view's force Jacobian pattern

 private:
  const CountedSystem& system_;
  const MassSpringView& view_;
  Eigen::VectorXd m_;                  // the lumped mass of each coordinate (dimension nodes x 1)
  double t0_ = 0, h_ = 0;
  Eigen::VectorXd x0_, xb_, f0_;       // f0: the forces other than the elastic ones, at the step's start
  Eigen::SparseMatrix<double> d0_;     // df/dv at the step's start (definite)
  mutable Eigen::VectorXd scratch_;
  mutable Eigen::SparseMatrix<double> k_;
  mutable StepMatrix step_matrix_;
};

// Newton on G, from `x` (a first guess) to the minimiser, in x: an inexact Newton (Dembo, Eisenstat & Steihaug 1982).
// The first direction comes from the sparse Cholesky factor (its analysis kept across steps) of G's exact Hessian at
// the first guess where it is positive definite, else of that Hessian with its mass term raised (A + tau M, tau from
// a quarter of the last raise that served, grown fourfold until the factor exists), else of the one made semidefinite
// element by element. (Projecting every element,
// as IPC does, drops the negative curvature of compressed springs that the mass term would carry: Newton then
// converges linearly, 0.88 an iteration on the flag's first step at 1/30 s.) The later directions solve
// A dx = -h^2 grad G (A = h^2 G's exact Hessian there) by conjugate gradients preconditioned by that factor, to a
// relative residual of Eisenstat & Walker's forcing term (loose far from the minimiser, quadratic convergence at the
// end). Where A is indefinite CG meets a direction of curvature p^T A p <= 0 and stops there, its iterate so far taken
// (Newton-CG's truncation, Nocedal & Wright's Algorithm 7.1: every CG iterate before it is a descent direction of G;
// at the first, the factor's direction itself); where CG needs more than max_cg_iterations, or its first
// cg_probe_iterations' rate predicts that it would, A is factored afresh the same way. (Factoring afresh at a
// non-positive curvature instead cost the continuum flag's first second 3.5 factorisations a frame, the mass term's
// raises most of them, against 2.6 truncated, both from a converged linearised first guess.) CG also stops where the
// correction the factor predicts (P^-1 r, on a factor of the exact Hessian) moves no node by a hundredth of what the
// velocity tolerance allows: the last direction of a step, which only has to show that it is short, then costs a few
// iterations. (A tenth saves a few more, but left the continuum flag's 14th step at 1/60 s 1% short of converged as
// exact Newton judges it: Cloth.NewtonsAnswerIsConvergedWhereConjugateGradientsMeetNegativeCurvature.) (A
// factor kept from an earlier step, as Gast et al. 2015 keep one, needs four times the CG iterations on the gusting
// continuum flag, and its directions lead Newton, on that buckling sheet, to another of backward Euler's solutions
// within seconds: 18 px away at 3 s.)
// Each step is halved until G falls by Armijo's fraction of the decrease the gradient predicts (a descent direction
// of a positive definite model always finds one). Converged when the step moves no node faster than
// `velocity_tolerance` (|dx|inf / h, as IPC judges it), or when the decrease it predicts is G's round-off
struct NewtonOnPotential {
  int max_iterations = 200;
  // m/s: a step's velocity error e moves the nodes e h a step, e T over a run of T seconds; a tenth of a pixel of the
  // flag's frame (1.5 m in 720 px: 2e-4 m) over its 5 s allows 4e-5 m/s, and 1e-5 keeps a factor of four
  double velocity_tolerance = 1e-5;
  Ordering ordering = Ordering::cheaper;
  // false: every direction from a fresh factor (exact Newton)
  bool inexact = true;
  double max_forcing = 0.1;
  // past this, CG has cost more than the factorisation it saves (one costs ~17 factor-preconditioned CG iterations on
  // the 32^2 flag: mass_spring_implicit.cpp)
  int max_cg_iterations = 20;
  // CG's first iterations, whose rate predicts whether the factor will serve within max_cg_iterations (0: none, CG
  // runs to max_cg_iterations before the factor is given up)
  int cg_probe_iterations = 4;
  // called at each iteration with G there and how fast Newton's step from there moves a node (m/s): the tests' view
  std::function<void(int iteration, double value, double moved)> observe;
};
class PotentialNewton {
 public:
  explicit PotentialNewton(NewtonOnPotential options) : options_(options) {}
  // "" when converged, else why not (naming the iteration, G's decrease and the last step); counts its iterations,
  // halvings, factorisations and solves into stats
  std::string minimise(const IncrementalPotential& potential, Eigen::VectorXd& x, Stats& stats);
  // the last factor (of the exact scaled Hessian at an iterate of the last step, or of its positive definite
  // modification), or null before the first: a preconditioner for a nearby matrix
  const SparseCholesky* factor() const { return factor_.factored() ? &factor_ : nullptr; }
  int max_cg_iterations() const { return options_.max_cg_iterations; }

 private:
  // the factor of a_ (the exact scaled Hessian at x) or of a positive definite modification of it
  std::string factor_positive_definite(const IncrementalPotential& potential, const Eigen::VectorXd& x, Stats& stats);
  // dx_ from CG on a_ dx = rhs_ preconditioned by the kept factor, to relative residual `forcing`, or to a correction
  // left that moves no node by more than `enough` (m), or to a direction of non-positive curvature (truncated there);
  // false where it did not converge in max_cg_iterations
  bool preconditioned_direction(double forcing, double enough, Stats& stats);
  NewtonOnPotential options_;
  double shift_ = 0;  // the last mass term raise that gave a factor (the largest, where none did)
  bool factored_exact_ = false;  // the factor is of the exact Hessian (not raised, not semidefinite)
  SparseCholesky factor_;
  bool analysed_ = false;
  Eigen::SparseMatrix<double> a_;
  Eigen::VectorXd g_, trial_, r_, p_, ap_;
  Eigen::MatrixXd z_;
  Eigen::MatrixXd rhs_, dx_;
};

}  // namespace stepwise
