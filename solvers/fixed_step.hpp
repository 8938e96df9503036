// Fixed-step integration: one loop over the step grid, shared by hand-written, GSL and GPU steppers.
#pragma once

#include "method.hpp"

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace stepwise {

class CountedSystem;

// one method's step y(t) -> y(t + h); made once per run, so it may keep state (multistep history)
class FixedStepper {
 public:
  virtual ~FixedStepper() = default;
  // y_next = y(t + h) from y = y(t) (two buffers, so the loop keeps the step's start without a copy); on
  // failure return false and say which call failed in `failure`
  virtual bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) = 0;
  // |y_next|inf of the last step, +inf if any entry is not finite, when the stepper measured it on its way
  // through the state: the loop's divergence test then needs no pass of its own
  virtual std::optional<double> last_norm() const { return std::nullopt; }
  // events the step handled itself (a contact method's impacts), as summary.json writes them ("impact"),
  // since the last call: the loop records them at the step's end
  virtual void take_events(std::vector<std::string>& kinds) { kinds.clear(); }
  // forget any history: the next step starts afresh (after an event changed the state, or to re-step)
  virtual void reset() {}
};

using FixedStepperFactory = std::function<std::unique_ptr<FixedStepper>(const CountedSystem& system)>;

// steps of exactly dt, the last one before each output time shortened to land on it
class FixedStepIntegrator final : public Integrator {
 public:
  // `method` is the table's entry (it outlives every run); BadMethod from integrate() for a system without
  // the structure the method needs
  FixedStepIntegrator(const Method& method, StepControl control, FixedStepperFactory make_stepper)
      : method_(method), control_(control), make_stepper_(std::move(make_stepper)) {}
  RunResult integrate(const OdeSystem& system, double t0, const Eigen::VectorXd& y0,
                      std::span<const double> t_out) const override;

 private:
  const Method& method_;
  StepControl control_;
  FixedStepperFactory make_stepper_;
};

// a fixed-step method's MakeIntegrator (method.hpp): the loop above around the steps `make_stepper` makes
MakeIntegrator fixed_steps(FixedStepperFactory make_stepper);

}  // namespace stepwise
