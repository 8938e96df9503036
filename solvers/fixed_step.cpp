#include "fixed_step.hpp"

#include "events.hpp"
#include "run_support.hpp"

#include <array>
#include <cmath>
#include <limits>

namespace stepwise {

RunResult FixedStepIntegrator::integrate(const OdeSystem& system, double t0, const Eigen::VectorXd& y0,
                                         std::span<const double> t_out) const {
  RunResult result = begin_run(t0, y0);
  const double start = thread_cpu_seconds();
  CountedSystem counted(system, result.stats);
  auto stepper = make_stepper_(counted);
  const double dt = *control_.dt;
  const double bound = divergence_bound(control_, y0);
  // a step ending within this of an output time lands on it instead of leaving a sliver
  const double snap = 1e-9 * dt;

  // y is the state at t, y_next the step's end: the two swap after each step, so the step's start is kept
  // (for events and for the last finite state of a diverging run) without copying the state
  Eigen::VectorXd y = y0, y_next(y0.size());
  double t = t0, h = dt;
  std::string failure;
  const auto events = system.events();
  std::vector<std::string> handled;
  Eigen::VectorXd g_start = event_values(events, t, y);
  // re-steps from the step's start to a fraction of it, for locating an event
  const Restep restep = [&](double s, Eigen::VectorXd& ys) {
    stepper->reset();
    return stepper->step(t, s * h, y, ys, failure);
  };
  for (const double target : t_out) {
    while (t < target) {
      double t_next = (target - (t + dt) <= snap) ? target : t + dt;
      h = t_next - t;
      if (!stepper->step(t, h, y, y_next, failure)) {
        mark_failed(result, t, failure);
        break;
      }
      ++result.stats.steps;
      stepper->take_events(handled);
      for (auto& kind : handled) record_event(result, t_next, std::move(kind), EventRecord::by_method);
      // back onto the manifold; a multistep history is kept (the correction is of the order of the local
      // error: restarting would drop GSL's multistep methods to order 1 for good, measured)
      counted.project(y_next);
      const auto norm = stepper->last_norm();
      if (norm ? !(*norm <= bound) : has_diverged(y_next, bound)) {
        mark_diverged(result, t_next);
        break;
      }
      // an event inside the step: move to it, apply its handler, and go on from there afresh
      if (const auto t_event = settle_step_events(events, g_start, t, h, y, y_next, control_.event_location, restep, result)) {
        stepper->reset();
        t_next = *t_event;
      }
      t = t_next;
      y.swap(y_next);
    }
    result.y_stop = y;
    if (result.status != Status::ok) break;
    record_output(result, control_, t, y);
  }
  result.stats.cpu_seconds = thread_cpu_seconds() - start;
  return result;
}

namespace {

// y1 = y0 + h f(t0, y0)
class Euler final : public FixedStepper {
 public:
  explicit Euler(const CountedSystem& s) : system_(s), f_(s.size()) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    system_.rhs(t, y, f_);
    y_next = y + h * f_;
    return true;
  }

 private:
  const CountedSystem& system_;
  Eigen::VectorXd f_;
};

// semi-implicit (symplectic) Euler on y = (x, v): v1 = v0 + h a(t0, x0, v0), x1 = x0 + h v1.
// Memory-bound on large systems (a particle system): after the acceleration, one pass over the state does
// both updates and the divergence norm; with a local acceleration the whole step is one pass, block by
// block, the block's acceleration never leaving cache
class SymplecticEuler final : public FixedStepper {
 public:
  explicit SymplecticEuler(const CountedSystem& s)
      : system_(s), n_(s.second_order()->positions), a_(s.has_local_acceleration() ? std::min(block, n_) : n_) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    const double* x0 = y.data();
    const double* v0 = x0 + n_;
    double* x1 = y_next.data();
    double* v1 = x1 + n_;
    Sweep sweep;
    const bool local = system_.has_local_acceleration();
    if (local) ++system_.stats().rhs_evals;
    else system_.acceleration(t, y, a_);
    for (Eigen::Index first = 0; first < n_; first += block) {
      const Eigen::Index count = std::min(block, n_ - first);
      const double* a = a_.data() + first;
      if (local) {
        system_.local_acceleration(t, x0 + first, v0 + first, a_.data(), first, count);
        a = a_.data();
      }
      sweep.update(h, x0 + first, v0 + first, a, x1 + first, v1 + first, count);
    }
    norm_ = sweep.bad ? std::numeric_limits<double>::infinity() : sweep.largest;
    return true;
  }
  std::optional<double> last_norm() const override { return norm_; }

 private:
  // entries per block: 3 x 8 KiB of x, v and a, well inside L1 and L2
  static constexpr Eigen::Index block = 1024;

  // v1 = v0 + h a, x1 = x0 + h v1 over a block, then |y_next|inf of the block while it is in cache (in
  // the update loop itself the max would stop it from vectorising: a NaN-exact max has no vector form)
  struct Sweep {
    double largest = 0;
    bool bad = false;  // some entry is inf or NaN
    // built twice, for AVX2 and for plain x86-64, the one chosen at load time (the same IEEE operations in
    // either, without fused multiply-adds, so the same bits)
    __attribute__((target_clones("avx2", "default"))) void update(double h, const double* __restrict x0, const double* __restrict v0, const double* __restrict a,
                double* __restrict x1, double* __restrict v1, Eigen::Index n) {
      for (Eigen::Index i = 0; i < n; ++i) {
        const double v = v0[i] + h * a[i];
        v1[i] = v;
        x1[i] = x0[i] + h * v;
      }
      // x - x is 0 for a finite entry and NaN otherwise, so the sums are 0 exactly when all are finite
      // (Eigen vectorises sums and plain maxima; its allFinite() and NaN-propagating max measured slower)
      const Eigen::Map<const Eigen::ArrayXd> x(x1, n), v(v1, n);
      if (!((x - x).sum() == 0 && (v - v).sum() == 0)) bad = true;
      else largest = std::max({largest, x.abs().maxCoeff(), v.abs().maxCoeff()});
    }
  };

  const CountedSystem& system_;
  Eigen::Index n_;
  Eigen::VectorXd a_;
  double norm_ = 0;
};

// classical fourth-order Runge-Kutta (Kutta 1901), four calls of f per step
class Rk4 final : public FixedStepper {
 public:
  explicit Rk4(const CountedSystem& s) : system_(s), k1_(s.size()), k2_(s.size()), k3_(s.size()), k4_(s.size()), tmp_(s.size()) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    system_.rhs(t, y, k1_);
    tmp_ = y + (h / 2) * k1_;
    system_.rhs(t + h / 2, tmp_, k2_);
    tmp_ = y + (h / 2) * k2_;
    system_.rhs(t + h / 2, tmp_, k3_);
    tmp_ = y + h * k3_;
    system_.rhs(t + h, tmp_, k4_);
    y_next = y + (h / 6) * (k1_ + 2 * k2_ + 2 * k3_ + k4_);
    return true;
  }

 private:
  const CountedSystem& system_;
  Eigen::VectorXd k1_, k2_, k3_, k4_, tmp_;
};

}  // namespace

std::unique_ptr<FixedStepper> make_euler(const CountedSystem& system) { return std::make_unique<Euler>(system); }
std::unique_ptr<FixedStepper> make_symplectic_euler(const CountedSystem& system) {
  if (!system.second_order())
    throw BadMethod("symplectic-euler needs a second-order system y = (x, v); this one is first order");
  return std::make_unique<SymplecticEuler>(system);
}
std::unique_ptr<FixedStepper> make_rk4(const CountedSystem& system) { return std::make_unique<Rk4>(system); }

}  // namespace stepwise
