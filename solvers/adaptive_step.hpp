// Adaptive integration: one loop over accepted steps, shared by GSL's evolve, Boost.Odeint's controlled
// steppers and the hand-written embedded pairs. Each lands on every output time, checks each accepted step
// for divergence, projects where the system has a projection, and finds events inside a step.
#pragma once

#include <stepwise/solvers/method.hpp>

#include <functional>
#include <memory>
#include <string>

namespace stepwise {

class CountedSystem;

// one method's error-controlled step; made once per run, so it may keep state (a first-same-as-last stage,
// a controller's history)
class AdaptiveStepper {
 public:
  virtual ~AdaptiveStepper() = default;
  // one accepted step from (t, y), at most to t_limit: advances t and y and proposes the next h (h in: the
  // step to try). Rejected trials are added to `rejected`. On failure return false and say which call failed
  // in `failure`; a step that produced non-finite values may return false too (the loop calls it diverged)
  virtual bool step(double& t, double t_limit, double& h, Eigen::VectorXd& y, long& rejected, std::string& failure) = 0;
  // y(t + h) from (t, y) in one untested step of size h: for locating an event inside the last accepted step
  // (where the stepper has dense output, its interpolant)
  virtual bool restep(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_out) = 0;
  // forget any history: the next step starts afresh (after an event changed the state)
  virtual void reset() {}
  // whether it interpolates within its last accepted step (dense output): then steps pass over output
  // times, which interpolate() fills in, rather than being cut short to land on each
  virtual bool dense() const { return false; }
  virtual void interpolate(double t, Eigen::VectorXd& y) { (void)t, (void)y; }
};

using AdaptiveStepperFactory = std::function<std::unique_ptr<AdaptiveStepper>(const CountedSystem& system, const StepControl& control)>;

class AdaptiveStepIntegrator final : public Integrator {
 public:
  // `method` is the table's entry; BadMethod from integrate() for a system without what it needs
  AdaptiveStepIntegrator(const Method& method, StepControl control, AdaptiveStepperFactory make_stepper)
      : method_(method), control_(std::move(control)), make_stepper_(std::move(make_stepper)) {}
  RunResult solve(const OdeSystem& system, double t0, const Eigen::VectorXd& y0, std::span<const double> t_out) const override;

 private:
  const Method& method_;
  StepControl control_;
  AdaptiveStepperFactory make_stepper_;
};

// the first trial step: a small fraction of the first output interval, within the cap; the control adapts it
double first_trial_step(const StepControl& control, const OdeSystem& system, double t0, std::span<const double> t_out);

}  // namespace stepwise
