#include "fixed_step.hpp"

#include "events.hpp"
#include "run_support.hpp"

#include <array>
#include <cmath>
#include <limits>

namespace stepwise {

RunResult FixedStepIntegrator::solve(const OdeSystem& system, double t0, const Eigen::VectorXd& y0,
                                         std::span<const double> t_out) const {
  if (!method_.needs.offered_by(system)) throw BadMethod(method_requirement(method_, system));
  RunResult result = begin_run(t0, y0);
  CountedSystem counted(system, result.stats);
  auto stepper = make_stepper_(counted);
  const double dt = *control_.dt;
  const double bound = divergence_bound(control_, stepper->norm(y0));
  // a step ending within this of an output time lands on it instead of leaving a sliver
  const double snap = 1e-9 * dt;

  // y is the state at t, y_next the step's end: the two swap after each step, so the step's start is kept
  // (for events and for the last finite state of a diverging run) without copying the state
  Eigen::VectorXd y = y0, y_next(y0.size());
  double t = t0, h = dt;
  std::string failure;
  const auto events = events_of(system);
  std::vector<std::string> handled;
  // what this system and method have, asked once: nothing is done per step for what they lack
  const bool watch_events = !events.empty();
  const bool method_events = stepper->handles_events();
  const Projection* projection = counted.as<Projection>();  // counted: its calls are; null where none
  EventWatch g_start = start_watch(events, t, y);
  // re-steps from the step's start to a fraction of it, for locating an event
  const Restep restep = [&](double s, Eigen::VectorXd& ys) {
    stepper->reset();
    return stepper->step(t, s * h, y, ys, failure);
  };
  // a run with none of these may have the stepper take its full steps itself (FixedStepper::plain_steps)
  const bool plain = !watch_events && !method_events && !projection && !control_.record_steps;
  bool stop = false;  // a terminal event or Zeno ended the run
  for (const double target : t_out) {
    while (t < target) {
      if (plain) {
        bool diverged = false;
        const long taken = stepper->plain_steps(t, dt, target, snap, bound, y, y_next, diverged);
        result.stats.steps += taken;
        if (diverged) [[unlikely]] {
          mark_diverged(result, t + dt);
          break;
        }
        if (taken > 0) continue;
      }
      double t_next = step_end(t, dt, target, snap);
      h = t_next - t;
      if (!stepper->step(t, h, y, y_next, failure)) [[unlikely]] {
        mark_failed(result, t, failure);
        break;
      }
      ++result.stats.steps;
      if (method_events) {
        stepper->take_events(handled);
        for (auto& kind : handled) record_event(result, t_next, std::move(kind), EventRecord::by_method);
      }
      // back onto the manifold; a multistep history is kept (the correction is of the order of the local
      // error: restarting would drop GSL's multistep methods to order 1 for good, measured)
      if (projection) projection->project(y_next);
      const auto norm = projection ? std::nullopt : stepper->last_norm();
      if (norm ? !(*norm <= bound) : has_diverged(y_next, bound)) [[unlikely]] {
        mark_diverged(result, t_next);
        break;
      }
      // an event inside the step: move to it, apply its handler, and go on from there afresh
      if (watch_events) {
        if (const auto settled = settle_step_events(events, g_start, t, h, y, y_next, control_.event_location, restep, result)) {
          stepper->reset();
          t_next = settled->t;
          stop = !settled->go_on;
        }
      }
      t = t_next;
      y.swap(y_next);
      if (stop) break;
      if (control_.record_steps && t < target && !record_output(result, control_, t, y)) break;
    }
    if (stop) {
      if (control_.record_steps && result.status == Status::ok) (void)record_output(result, control_, t, y);
      break;
    }
    result.y_stop = y;
    if (result.status != Status::ok || !record_output(result, control_, t, y)) break;
  }
  return result;
}

MakeIntegrator fixed_steps(FixedStepperFactory make_stepper) {
  return [make_stepper = std::move(make_stepper)](const Method& method, const StepControl& control) {
    return std::make_unique<FixedStepIntegrator>(method, control, make_stepper);
  };
}

}  // namespace stepwise
