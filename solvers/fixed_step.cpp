#include "fixed_step.hpp"

#include "events.hpp"
#include "run_support.hpp"

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
  double t = t0;
  std::string failure;
  const auto events = system.events();
  Eigen::VectorXd g_start = event_values(events, t, y);
  for (const double target : t_out) {
    while (t < target) {
      double t_next = (target - (t + dt) <= snap) ? target : t + dt;
      const double h = t_next - t;
      if (!stepper->step(t, h, y, y_next, failure)) {
        mark_failed(result, t, failure);
        break;
      }
      ++result.stats.steps;
      const auto norm = stepper->last_norm();
      if (norm ? !(*norm <= bound) : has_diverged(y_next, bound)) {
        mark_diverged(result, t_next);
        break;
      }
      // an event inside the step: move to it, apply its handler, and go on from there afresh
      const Restep restep = [&](double s, Eigen::VectorXd& ys) {
        stepper->reset();
        return stepper->step(t, s * h, y, ys, failure);
      };
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
// Memory-bound on large systems (a particle system), so it makes one pass over the state after the
// acceleration: both updates and the divergence norm together
class SymplecticEuler final : public FixedStepper {
 public:
  explicit SymplecticEuler(const CountedSystem& s) : system_(s), a_(s.second_order()->positions), n_(s.second_order()->positions) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    system_.acceleration(t, y, a_);
    const double* x0 = y.data();
    const double* v0 = x0 + n_;
    const double* a = a_.data();
    double* x1 = y_next.data();
    double* v1 = x1 + n_;
    double largest = 0, nonfinite = 0;  // |y_next|inf, and a sum that is 0 unless some entry is inf or NaN
    for (Eigen::Index k = 0; k < n_; ++k) {
      const double v = v0[k] + h * a[k];
      const double x = x0[k] + h * v;
      v1[k] = v;
      x1[k] = x;
      largest = std::max(largest, std::max(std::abs(x), std::abs(v)));
      nonfinite += (x - x) + (v - v);
    }
    norm_ = nonfinite == 0 ? largest : std::numeric_limits<double>::infinity();
    return true;
  }
  std::optional<double> last_norm() const override { return norm_; }

 private:
  const CountedSystem& system_;
  Eigen::VectorXd a_;
  Eigen::Index n_;
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
