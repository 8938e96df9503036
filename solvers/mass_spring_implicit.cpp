#include "mass_spring_implicit.hpp"

#include "run_support.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace stepwise {

BaraffWitkinSystem::BaraffWitkinSystem(const OdeSystem& system, bool definite)
    : system_(system), definite_(definite), f_(system.size() / 2), b_(system.size() / 2) {
  const MassSpringView* view = system.mass_spring();
  if (!view) throw std::invalid_argument("BaraffWitkinSystem: the system has no mass-spring structure");
  m_.resize(3 * Eigen::Index{view->nodes});
  for (int i = 0; i < view->nodes; ++i) m_.segment<3>(3 * i).setConstant(view->mass[i]);
}

void BaraffWitkinSystem::assemble_matrix(double t, const Eigen::VectorXd& y, double h) {
  system_.force_jacobians(t, y, definite_, k_, d_);
  // force_jacobians keeps its pattern from call to call: whether K, D and A share one is found at the first
  // call, and then A's values come straight from theirs
  if (shared_pattern_) {
    const double* k = k_.valuePtr();
    const double* d = d_.valuePtr();
    double* a = a_.valuePtr();
    for (Eigen::Index s = 0; s < a_.nonZeros(); ++s) a[s] = -h * d[s] - h * h * k[s];
    a_.diagonal() += m_;
  } else {
    const bool first = a_.nonZeros() == 0;
    Eigen::SparseMatrix<double> mass(m_.size(), m_.size());
    mass.setIdentity();
    mass.diagonal() = m_;
    a_ = mass - h * d_ - (h * h) * k_;
    a_.makeCompressed();
    shared_pattern_ = first && k_.nonZeros() == d_.nonZeros() && k_.nonZeros() == a_.nonZeros() &&
                      std::equal(k_.innerIndexPtr(), k_.innerIndexPtr() + k_.nonZeros(), d_.innerIndexPtr()) &&
                      std::equal(k_.innerIndexPtr(), k_.innerIndexPtr() + k_.nonZeros(), a_.innerIndexPtr());
  }
  system_.acceleration(t, y, f_);
  f_ = f_.cwiseProduct(m_);
}

void BaraffWitkinSystem::assemble_rhs(const Eigen::VectorXd& y, double h) {
  const Eigen::Index n = m_.size();
  b_ = h * (f_ + h * (k_ * y.tail(n)));
}

namespace {

constexpr int max_direct_run = 64;

// CG's preconditioner: the kept CHOLMOD factor of an earlier matrix (Eigen's preconditioner interface; the
// factor is managed by the stepper, so compute does nothing)
class KeptFactor {
 public:
  KeptFactor() = default;
  template <class Matrix>
  KeptFactor& analyzePattern(const Matrix&) { return *this; }
  template <class Matrix>
  KeptFactor& factorize(const Matrix&) { return *this; }
  template <class Matrix>
  KeptFactor& compute(const Matrix&) { return *this; }
  Eigen::ComputationInfo info() const { return Eigen::Success; }
  template <class Rhs>
  Eigen::VectorXd solve(const Rhs& r) const {
    rhs_ = r;
    // a failed solve (CHOLMOD out of memory) poisons the iteration, which then fails to converge and the
    // stepper refactorises, where the failure is reported by name
    if (!factor_->solve(rhs_, out_).empty()) out_.setConstant(rhs_.rows(), 1, std::numeric_limits<double>::quiet_NaN());
    return out_.col(0);
  }
  void use(const SparseCholesky* factor) { factor_ = factor; }

 private:
  const SparseCholesky* factor_ = nullptr;
  mutable Eigen::MatrixXd rhs_, out_;
};

class MassSpringImplicit final : public FixedStepper {
 public:
  MassSpringImplicit(const CountedSystem& s, const MassSpringImplicitOptions& options)
      : system_(s), options_(options), bw_(s, options.definite), n_(s.size() / 2) {
    cg_.setTolerance(options.cg_residual);
    cg_.setMaxIterations(options.cg_max_iterations);
  }

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) override {
    bw_.assemble_matrix(t, y, h);
    bw_.assemble_rhs(y, h);
    if (!solve(t, failure)) return false;
    y_next.resize(y.size());
    y_next.tail(n_) = y.tail(n_) + dv_;
    y_next.head(n_) = y.head(n_) + h * y_next.tail(n_);
    if (!options_.newton) return true;

    const double t1 = t + h;
    for (int iteration = 0; iteration < options_.newton_max_iterations; ++iteration) {
      // the residual at the iterate, and the matrix there
      bw_.assemble_matrix(t1, y_next, h);
      residual_ = bw_.mass().cwiseProduct(y_next.tail(n_) - y.tail(n_)) - h * bw_.force();
      const double scale = bw_.mass().cwiseProduct(y_next.tail(n_)).norm() + h * bw_.force().norm();
      if (!residual_.allFinite()) break;
      if (residual_.norm() <= options_.newton_residual * scale || residual_.norm() == 0) return true;
      rhs_ = -residual_;
      if (!solve(t, failure, &rhs_)) return false;
      y_next.tail(n_) += dv_;
      y_next.head(n_) = y.head(n_) + h * y_next.tail(n_);
    }
    ++system_.stats().rejected;
    failure = fmt::format("implicit-euler-newton: the Newton iteration did not reach a residual of {:.1e} in {} iterations at t = {:.9g} (h = {:.3g})",
                          options_.newton_residual, options_.newton_max_iterations, t, h);
    return false;
  }

 private:
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
    if (options_.solve == LinearSolve::refactor || !analysed_ || direct_left_ > 0) {
      if (direct_left_ > 0) --direct_left_;
      return direct();
    }
    // conjugate gradients preconditioned by the kept factor of an earlier matrix, from the last step's dv
    // (a cloth's velocity changes smoothly, so it starts closer than zero does), for at most as many
    // iterations as a refactorisation costs: past that the factor has stopped paying
    const double limit = solve_seconds_ > 0 ? 1 + factor_seconds_ / solve_seconds_ : 2;
    cg_.setMaxIterations(std::clamp(static_cast<int>(limit) - 1, 1, options_.cg_max_iterations));
    cg_.preconditioner().use(&factor_);
    cg_.compute(bw_.matrix());
    const double start = thread_cpu_seconds();
    dv_ = cg_.solveWithGuess(b, rhs ? Eigen::VectorXd::Zero(b.size()) : guess_);
    const long solves = cg_.iterations() + 1;  // Eigen counts the iterations after the first
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
  int reuses_ = 0;        // CG solves with the present factor
  int direct_left_ = 0;   // solves still to refactorise directly
  int direct_run_ = 1;    // how many the next failed trial of a kept factor refactorises directly
  double factor_seconds_ = 0, solve_seconds_ = 0;  // thread CPU time of the last factorisation, and of one CG iteration
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper, KeptFactor> cg_;
  Eigen::VectorXd dv_, residual_, rhs_, guess_;
  Eigen::MatrixXd b_, x_;
};

}  // namespace

std::unique_ptr<FixedStepper> make_mass_spring_implicit(const CountedSystem& system, const MassSpringImplicitOptions& options) {
  return std::make_unique<MassSpringImplicit>(system, options);
}

}  // namespace stepwise
