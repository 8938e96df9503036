#include "fixed_step.hpp"

#include "events.hpp"
#include "run_support.hpp"

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

  Eigen::VectorXd y = y0, y_start;
  double t = t0;
  std::string failure;
  const auto events = system.events();
  Eigen::VectorXd g_start = event_values(events, t, y);
  for (const double target : t_out) {
    while (t < target) {
      double t_next = (target - (t + dt) <= snap) ? target : t + dt;
      const double h = t_next - t;
      y_start = y;
      if (!stepper->step(t, h, y, failure)) {
        mark_failed(result, t, failure);
        break;
      }
      ++result.stats.steps;
      if (has_diverged(y, bound)) {
        mark_diverged(result, t_next);
        break;
      }
      // an event inside the step: move to it, apply its handler, and go on from there afresh
      const Restep restep = [&](double s, Eigen::VectorXd& ys) {
        stepper->reset();
        ys = y_start;
        return stepper->step(t, s * h, ys, failure);
      };
      if (const auto t_event = settle_step_events(events, g_start, t, h, y_start, y, control_.event_location, restep, result)) {
        stepper->reset();
        t_next = *t_event;
      }
      t = t_next;
      result.y_stop = y;
    }
    if (result.status != Status::ok) break;
    record_output(result, t, y);
  }
  result.stats.cpu_seconds = thread_cpu_seconds() - start;
  return result;
}

namespace {

// y1 = y0 + h f(t0, y0)
class Euler final : public FixedStepper {
 public:
  explicit Euler(const CountedSystem& s) : system_(s), f_(s.size()) {}
  bool step(double t, double h, Eigen::VectorXd& y, std::string&) override {
    system_.rhs(t, y, f_);
    y += h * f_;
    return true;
  }

 private:
  const CountedSystem& system_;
  Eigen::VectorXd f_;
};

// semi-implicit (symplectic) Euler on y = (x, v): v1 = v0 + h a(t0, x0, v0), x1 = x0 + h v1
class SymplecticEuler final : public FixedStepper {
 public:
  explicit SymplecticEuler(const CountedSystem& s) : system_(s), f_(s.size()), n_(s.second_order()->positions) {}
  bool step(double t, double h, Eigen::VectorXd& y, std::string&) override {
    system_.rhs(t, y, f_);
    y.segment(n_, n_) += h * f_.segment(n_, n_);
    y.head(n_) += h * y.segment(n_, n_);
    return true;
  }

 private:
  const CountedSystem& system_;
  Eigen::VectorXd f_;
  int n_;
};

// classical fourth-order Runge-Kutta (Kutta 1901), four calls of f per step
class Rk4 final : public FixedStepper {
 public:
  explicit Rk4(const CountedSystem& s) : system_(s), k1_(s.size()), k2_(s.size()), k3_(s.size()), k4_(s.size()), tmp_(s.size()) {}
  bool step(double t, double h, Eigen::VectorXd& y, std::string&) override {
    system_.rhs(t, y, k1_);
    tmp_ = y + (h / 2) * k1_;
    system_.rhs(t + h / 2, tmp_, k2_);
    tmp_ = y + (h / 2) * k2_;
    system_.rhs(t + h / 2, tmp_, k3_);
    tmp_ = y + h * k3_;
    system_.rhs(t + h, tmp_, k4_);
    y += (h / 6) * (k1_ + 2 * k2_ + 2 * k3_ + k4_);
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
