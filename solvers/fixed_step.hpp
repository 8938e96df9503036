// Fixed-step integration: one loop over the step grid, shared by hand-written and GSL steppers.
#pragma once

#include "integrator.hpp"

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

// a fixed-step method of the table whose stepper another library makes (the GPU shader methods of
// solvers/gpu/, which need render/'s GL context), registered by that library before any run
// (gpu::register_gpu_methods); make_integrator finds it by name
void register_stepper(std::string_view method, FixedStepperFactory factory);

// steps of exactly dt, the last one before each output time shortened to land on it
class FixedStepIntegrator final : public Integrator {
 public:
  FixedStepIntegrator(std::string method, StepControl control, FixedStepperFactory make_stepper)
      : method_(std::move(method)), control_(control), make_stepper_(std::move(make_stepper)) {}
  RunResult integrate(const OdeSystem& system, double t0, const Eigen::VectorXd& y0,
                      std::span<const double> t_out) const override;

 private:
  std::string method_;
  StepControl control_;
  FixedStepperFactory make_stepper_;
};

// the hand-written steppers of DESIGN.md's table
std::unique_ptr<FixedStepper> make_euler(const CountedSystem& system);
std::unique_ptr<FixedStepper> make_symplectic_euler(const CountedSystem& system);
std::unique_ptr<FixedStepper> make_rk4(const CountedSystem& system);
// backward Euler: on a mass-spring system Baraff & Witkin's linearised step on CHOLMOD (mass_spring_implicit.hpp),
// otherwise Newton's method to convergence on a dense (or sparse) matrix
std::unique_ptr<FixedStepper> make_implicit_euler(const CountedSystem& system);
// backward Euler iterated to convergence: on a mass-spring system by Newton on CHOLMOD, otherwise as above
std::unique_ptr<FixedStepper> make_implicit_euler_newton(const CountedSystem& system);
// Liu et al. 2013's prefactored local/global method; the system has a mass_spring()
std::unique_ptr<FixedStepper> make_fast_mass_spring(const CountedSystem& system);
// the seeds' three-level scheme for a wave equation on a grid (wave_step.hpp); the system has a wave_grid()
std::unique_ptr<FixedStepper> make_wave_fd(const CountedSystem& system);
// the free rigid body's splitting into exact rotations; the system has a free_rigid_body()
std::unique_ptr<FixedStepper> make_rigid_splitting(const CountedSystem& system);
// kick, contact impulses, drift for rigid bodies in contact; the system has contact_bodies()
std::unique_ptr<FixedStepper> make_contact_stepping(const CountedSystem& system);

}  // namespace stepwise
