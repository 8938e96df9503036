#include "adaptive_step.hpp"

#include "events.hpp"
#include "run_support.hpp"

namespace stepwise {

double first_trial_step(const StepControl& control, const OdeSystem& system, double t0, std::span<const double> t_out) {
  return std::min(max_adaptive_step(control, system), 1e-3 * (t_out.front() - t0));
}

namespace {

// a time step so short, at t, that one Euler step over it errs by round-off alone: h^2 / 2 at 1e-10 max(1, |t|)
double sliver(double t) { return 1e-10 * std::max(1.0, std::abs(t)); }

}  // namespace

RunResult AdaptiveStepIntegrator::solve(const OdeSystem& system, double t0, const Eigen::VectorXd& y0,
                                            std::span<const double> t_out) const {
  if (!method_.needs.offered_by(system)) throw BadMethod(method_requirement(method_, system));
  RunResult result = begin_run(t0, y0);
  CountedSystem counted(system, result.stats);
  auto stepper = make_stepper_(counted, control_);
  const double max_step = max_adaptive_step(control_, system);
  const double bound = divergence_bound(control_, y0);
  double h = first_trial_step(control_, system, t0, t_out);

  Eigen::VectorXd y = y0, y_start;  // y_start: the step's start, for events and a failing step
  double t = t0, t_start = t0, taken = 0;
  std::string failure;
  const auto events = events_of(system);
  const bool watch_events = !events.empty();
  const Projection* projection = counted.as<Projection>();  // counted: its calls are; null where none
  EventWatch g_start = start_watch(events, t, y);
  // re-steps from the step's start to a fraction of it, for locating an event
  const Restep restep = [&](double s, Eigen::VectorXd& ys) { return stepper->restep(t_start, s * taken, y_start, ys); };
  // the outputs are recorded as steps pass them: at a step's end, or, with dense output, interpolated inside it
  const bool dense = stepper->dense();
  Eigen::VectorXd y_out;
  size_t next = 0;
  double last_recorded = t0;  // the latest time the trajectory holds (outputs and, recording steps, step ends)
  while (next < t_out.size()) {
    const double target = dense ? t_out.back() : t_out[next];
    y_start = y;
    t_start = t;
    if (result.stats.steps >= control_.max_steps) {
      mark_failed(result, t, fmt::format("{}: more than {} steps before t = {:.9g}", method_.name, control_.max_steps, t_out[next]));
      break;
    }
    h = std::min(h, max_step);
    if (!dense && target - t <= sliver(t)) {
      // an output a sliver after t (an event located just short of it): shorter than a step the error control of
      // some methods can take (GSL's bsimp fails on 3e-13 s at t = 39.5), and one Euler step there is exact to
      // round-off (its error h^2 |y''| / 2)
      Eigen::VectorXd f(y.size());
      counted.rhs(t, y, f);
      y += (target - t) * f;
      t = target;
    } else if (!stepper->step(t, target, h, y, result.stats.rejected, failure)) {
      if (failure.empty() || has_diverged(y, bound)) mark_diverged(result, t);
      else mark_failed(result, t, failure);
      break;
    }
    ++result.stats.steps;
    // back onto the manifold, keeping the stepper's state: the correction is of the order of the local error
    if (projection) projection->project(y);
    if (has_diverged(y, bound)) {
      mark_diverged(result, t);
      break;
    }
    // an event inside the accepted step: locate it, apply its handler, restart the stepper there
    bool stop = false;  // a terminal event or Zeno ended the run
    if (watch_events) {
      taken = t - t_start;
      if (const auto settled = settle_step_events(events, g_start, t_start, taken, y_start, y, control_.event_location, restep, result)) {
        t = settled->t;
        stop = !settled->go_on;
        stepper->reset();
      }
    }
    for (; next < t_out.size() && (t_out[next] <= t || same_instant(t_out[next], t)) && result.status == Status::ok; ++next) {
      const bool at_t = same_instant(t_out[next], t);
      if (stop && at_t) break;  // the event's time is recorded below, where steps are
      if (!at_t) stepper->interpolate(t_out[next], y_out);
      if (!record_output(result, control_, t_out[next], at_t ? y : y_out)) break;
      last_recorded = t_out[next];
    }
    if (result.status != Status::ok) break;
    if (control_.record_steps && t > last_recorded) {
      if (!record_output(result, control_, t, y)) break;
      last_recorded = t;
    }
    if (stop) {
      // the run ends at the event: the outputs recorded before it moved t_stop back to theirs
      result.t_stop = t;
      result.y_stop = y;
      break;
    }
  }
  if (result.status != Status::ok) result.y_stop = y_start;  // the last finite state: the start of the step that failed
  return result;
}

}  // namespace stepwise
