#include "mass_spring_implicit.hpp"

#include "incremental_potential.hpp"
#include "run_support.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace stepwise {

namespace {

const MassSpringView& mass_spring_of(const OdeSystem& system) {
  const auto* view = system.as<MassSpringView>();
  if (!view) throw std::invalid_argument("BaraffWitkinSystem: the system has no mass-spring structure");
  return *view;
}

}  // namespace

BaraffWitkinSystem::BaraffWitkinSystem(const CountedSystem& system, bool definite)
    : system_(system), view_(mass_spring_of(system)), definite_(definite), m_(coordinate_masses(view_)), f_(system.size() / 2),
      b_(system.size() / 2) {}

void BaraffWitkinSystem::assemble_matrix(double t, const Eigen::VectorXd& y, double h) {
  force_jacobians(system_, view_, t, y, definite_, k_, d_);
  step_matrix_(m_, d_, k_, h, a_);
  assemble_force(t, y);
}

void BaraffWitkinSystem::assemble_force(double t, const Eigen::VectorXd& y) {
  second_order_acceleration(system_, *system_.as<SecondOrderView>(), t, y, f_, scratch_);
  f_ = f_.cwiseProduct(m_);
}

void BaraffWitkinSystem::assemble_exact(double t, const Eigen::VectorXd& y, double h) {
  force_jacobians(system_, view_, t, y, false, exact_k_, exact_d_);
  exact_step_matrix_(m_, exact_d_, exact_k_, h, j_);
}

void BaraffWitkinSystem::assemble_rhs(const Eigen::VectorXd& y, double h) {
  const Eigen::Index n = m_.size();
  b_ = h * (f_ + h * (k_ * y.tail(n)));
}

namespace {

constexpr int max_direct_run = 64;
constexpr int probe_iterations = 3;  // the kept factor's first CG iterations, whose rate predicts the rest
// the relative residual of the linearised step as Newton's first guess: a hundredth, Newton's first forcing term
// (Eisenstat & Walker's, max_forcing 0.1) a tenth again, as the guess carries no line search
constexpr double guess_residual = 1e-2;

class MassSpringImplicit final : public FixedStepper {
 public:
  MassSpringImplicit(const CountedSystem& s, const MassSpringImplicitOptions& options)
      : system_(s), options_(options), bw_(s, options.definite), n_(s.size() / 2), potential_(s, mass_spring_of(s)),
        newton_(NewtonOnPotential{.ordering = options.ordering, .inexact = !options.exact_newton}) {
    cg_.setTolerance(options.cg_residual);
    cg_.setMaxIterations(options.cg_max_iterations);
  }

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) override {
    bw_.assemble_matrix(t, y, h);
    bw_.assemble_rhs(y, h);
    const bool guess = options_.newton && options_.solve == LinearSolve::kept_factor && newton_.factor();
    if (!(guess ? first_guess(t, failure) : solve(t, failure))) return false;
    y_next.resize(y.size());
    y_next.tail(n_) = y.tail(n_) + dv_;
    y_next.head(n_) = y.head(n_) + h * y_next.tail(n_);
    if (!options_.newton) return true;

    // backward Euler itself: Newton on the incremental potential G (incremental_potential.hpp), from the
    // linearised step's answer, to the step's velocity tolerance
    if (options_.definite)
      potential_.start(t, y, h, bw_.force(), bw_.damping());  // the linearised step's f and D at (t, y): D0 is the definite D
    else
      potential_.start(t, y, h);
    x_newton_ = y_next.head(n_);
    if (const std::string why = newton_.minimise(potential_, x_newton_, system_.stats()); !why.empty()) {
      ++system_.stats().rejected;
      failure = fmt::format("implicit-euler-newton: Newton on the incremental potential {} at t = {:.9g} (h = {:.3g})", why, t, h);
      return false;
    }
    y_next.tail(n_) = (x_newton_ - y.head(n_)) / h;
    guess_ = y_next.tail(n_) - y.tail(n_);  // the next first guess's CG starts from this step's dv
    y_next.head(n_) = x_newton_;
    return true;
  }

 private:
  // with Newton after it (and factors kept), the linearised step is only Newton's first guess (its step from
  // x0 + h v0 on the definite Hessian at the step's start) and is solved inexactly, as Newton's own later directions
  // are: CG preconditioned by Newton's last factor (of the exact Hessian at an iterate of the last step, near this
  // step's start: fresher than a factor the linearised step keeps), from the last step's dv, to a relative residual
  // of guess_residual, or for at most Newton's CG iterations, the iterate then taken. Newton moves on from wherever it
  // lands: a converged guess saves it no iteration, and costs factorisations (measured against this and against
  // Newton's factor for the tight solve: docs/performance-cloth.md, backward Euler's Newton)
  bool first_guess(double t, std::string& failure) {
    cg_.preconditioner().use(newton_.factor());
    cg_.compute(bw_.matrix());
    cg_.setTolerance(guess_residual);
    cg_.setMaxIterations(newton_.max_cg_iterations());
    dv_ = cg_.solveWithGuess(bw_.rhs(), guess_);
    cg_.setTolerance(options_.cg_residual);
    system_.stats().linear_solves += cg_.iterations() + 1;
    if (dv_.allFinite()) return true;
    return solve(t, failure);  // CG broke down (a failed triangular solve): the linearised step's own way
  }

  // dv = A^-1 b (the system's rhs, or `rhs`) by the option's way; false with the failing call named
  bool solve(double t, std::string& failure, const Eigen::VectorXd* rhs = nullptr) {
    const Eigen::VectorXd& b = rhs ? *rhs : bw_.rhs();
    const auto refactor = [&]() {
      if (!analysed_) {
        if (auto e = factor_.analyze(bw_.matrix(), options_.ordering); !e.empty()) {
          failure = fmt::format("implicit-euler: {} at t = {:.9g}", e, t);
          return false;
        }
        analysed_ = true;
      }
      ++system_.stats().factorizations;
      const double start = thread_cpu_seconds();
      const std::string e = factor_.factorize(bw_.matrix());
      factor_seconds_ = thread_cpu_seconds() - start;
      factored_ = e.empty();
      if (!e.empty()) {
        failure = fmt::format("implicit-euler: {} at t = {:.9g}", e, t);
        return false;
      }
      reuses_ = 0;
      return true;
    };
    // a fresh factor (of this very matrix) solves directly; CG would stop after its first iteration
    const auto direct = [&]() {
      if (!refactor()) return false;
      ++system_.stats().linear_solves;
      b_ = b;
      const double start = thread_cpu_seconds();
      const std::string e = factor_.solve(b_, x_);
      if (solve_seconds_ == 0) solve_seconds_ = thread_cpu_seconds() - start;  // until CG times its own iterations
      if (!e.empty()) {
        failure = fmt::format("implicit-euler: {} at t = {:.9g}", e, t);
        return false;
      }
      dv_ = x_.col(0);
      if (!rhs) guess_ = dv_;
      return true;
    };
    if (options_.solve == LinearSolve::refactor || !factored_ || direct_left_ > 0) {
      if (direct_left_ > 0) --direct_left_;
      return direct();
    }
    // conjugate gradients preconditioned by the kept factor of an earlier matrix, from the last step's dv
    // (a cloth's velocity changes smoothly, so it starts closer than zero does), for at most as many
    // iterations as a refactorisation costs: past that the factor has stopped paying. A fresh factor's first
    // reuse (the trial of whether it pays at all) starts with a probe of a few iterations: preconditioned
    // CG converges about geometrically here, so the rate it shows predicts the iterations the tolerance
    // needs, and a factor that would not pay is given up after the probe instead of after a
    // refactorisation's worth of iterations (on the gusting flag a one-step-old factor needs 19-42 where
    // 17 cost a refactorisation: each failed trial cost twice a step). Later reuses, whose factor has
    // paid, run straight on (a restart after the probe costs a solve)
    const double limit = solve_seconds_ > 0 ? 1 + factor_seconds_ / solve_seconds_ : 2;
    const int budget = std::clamp(static_cast<int>(limit) - 1, 1, options_.cg_max_iterations);
    const Eigen::VectorXd guess = rhs ? Eigen::VectorXd::Zero(b.size()) : guess_;
    cg_.preconditioner().use(&factor_);
    cg_.compute(bw_.matrix());
    const double start = thread_cpu_seconds();
    const int first_run = reuses_ == 0 ? std::min(probe_iterations, budget) : budget;
    // the probe's starting residual, relative as Eigen's error() is (a product with A, only when probing)
    const double start_error = first_run < budget ? (b - bw_.matrix() * guess).norm() / b.norm() : 0;
    cg_.setMaxIterations(first_run);
    dv_ = cg_.solveWithGuess(b, guess);
    long solves = cg_.iterations() + 1;  // Eigen counts the iterations after the first
    if (cg_.info() != Eigen::Success && budget > first_run) {
      const int done = std::max(static_cast<int>(cg_.iterations()), 1);
      if (predicted_iterations(start_error, cg_.error(), done, options_.cg_residual) <= budget) {
        cg_.setMaxIterations(budget - cg_.iterations());
        dv_ = cg_.solveWithGuess(b, Eigen::VectorXd(dv_));
        solves += cg_.iterations() + 1;
      }
    }
    solve_seconds_ = (thread_cpu_seconds() - start) / static_cast<double>(solves);
    system_.stats().linear_solves += solves;
    ++reuses_;
    if (cg_.info() == Eigen::Success) {
      if (!rhs) guess_ = dv_;
      if (reuses_ > 1) direct_run_ = 1;
      return true;
    }
    // the kept factor no longer pays: refactorise and solve; if it did not pay even once, refactorise
    // directly for a run of solves before trying a kept factor again
    if (reuses_ == 1) {
      direct_left_ = direct_run_;
      direct_run_ = std::min(2 * direct_run_, max_direct_run);
    }
    return direct();
  }

  const CountedSystem& system_;
  MassSpringImplicitOptions options_;
  BaraffWitkinSystem bw_;
  Eigen::Index n_;
  SparseCholesky factor_;
  bool analysed_ = false;
  bool factored_ = false;  // the factor holds a matrix's (a failed factorisation leaves none to keep)
  int reuses_ = 0;        // CG solves with the present factor
  int direct_left_ = 0;   // solves still to refactorise directly
  int direct_run_ = 1;    // how many the next failed trial of a kept factor refactorises directly
  double factor_seconds_ = 0, solve_seconds_ = 0;  // thread CPU time of the last factorisation, and of one CG iteration
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper, FactorPreconditioner> cg_;
  IncrementalPotential potential_;
  PotentialNewton newton_;
  Eigen::VectorXd dv_, guess_, x_newton_;
  Eigen::MatrixXd b_, x_;
};

}  // namespace

std::unique_ptr<FixedStepper> make_mass_spring_implicit(const CountedSystem& system, const MassSpringImplicitOptions& options) {
  return std::make_unique<MassSpringImplicit>(system, options);
}

}  // namespace stepwise
