// Events between two step ends: detection by the sign of g, and location on the step.
//
// The seeds' method (collision of a particle with a plane): when the signed distance g changes sign over
// a step, the crossing time is estimated on the segment p(t) -> p(t + h), where the linear interpolant of g
// vanishes, s = g0 / (g0 - g1), and the state is carried there by one step of h s from the step's start
// (the model's handler then moves the particle onto the surface). The refinement repeats such steps,
// s found by the Illinois variant of regula falsi on g, until g is zero to round-off.
//
// A user's event (Event::surface false) is always refined so, on the method's own solution: the re-step
// is the stepper's interpolant where it has dense output, else a step of h s from the step's start. Where
// g has the same sign at both ends but its rate dg/dt changes sign, the extremum between is found (the root
// of the rate, refined the same way) and tested: a pair of roots inside one step (a graze, a flight shorter
// than the step) is seen. Several extrema inside one step are not (the rates at the ends agree): the step
// must be shorter than the time between them (max_step).
#pragma once

#include <stepwise/solvers/integrator.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace stepwise {

// g_i(t, y) for every event, into g (sized to the events)
void event_values(std::span<const Event> events, double t, const Eigen::VectorXd& y, Eigen::VectorXd& g);

// what the event pass keeps between steps: g at the step's start, and the level each event's g is measured from.
// That is 0, but for a user's event just handled it is g right after the handlers: the state sits on the
// event's zero to the root's precision (a ball at y = -1e-15), and its next crossing is of that level (a
// flight of 1e-22 m above it is still a flight)
struct EventWatch {
  Eigen::VectorXd g, zero;
  Eigen::VectorXd g_end;        // scratch: g at the step's end (kept, so that a step allocates nothing)
  std::vector<char> fired;      // the user's events handled at the step's start (one entry an event)
  Eigen::VectorXd fired_rate;   // each one's g's rate at the instant, before the handlers
};
EventWatch start_watch(std::span<const Event> events, double t, const Eigen::VectorXd& y);

// the events that reach zero at one instant t (`indices`, ascending: the order the system declares them), handled
// there each once, each handler reading the state the previous one left. False when the run ends here: at Zeno
// (failed, at once), or at a terminal event among them, after the others of the instant have fired too (at one
// instant no event comes after another), t_stop and y_stop then at the state after them all
[[nodiscard]] bool handle_events(RunResult& result, std::span<const Event> events, std::span<const size_t> indices, double t, Eigen::VectorXd& y);

// why a run fails where event `event`'s g is not finite (g) at t: its name, the value and the time
std::string not_finite_event(const Event& event, double g, double t);

// recomputes the state at fraction s of the step from its start; false when the step fails
using Restep = std::function<bool(double s, Eigen::VectorXd& y)>;

// where an event fired inside a step, and whether the run goes on after it
struct Settled {
  double t;
  bool go_on;  // false: a terminal event, or Zeno (the result says which)
};

// After a step (t, y_start) -> (t + h, y): if events fired inside it, carry y to the earliest instant one did,
// apply the handlers of every event that reaches zero at that instant (handle_events: each once, in the order the
// system declares them), recording what happened in result, and return the instant; either way the watch moves to
// the new end of the step. An event whose g is not finite at the step's end fails the run there, naming it. The
// one event pass of every integrator that steps by itself (fixed-step, GSL, the hand-written adaptive pairs).
//
// One instant: the roots are found to where g is within 4 eps of the larger of its values at the bracket's ends
// (or the bracket is 1e-15 of the step wide), so two events whose true roots coincide are located at most
// 2e-15 h + 2 eps |t| apart (the widths, and the rounding of t + s h). Events located within that of the
// earliest, or whose g at the earliest's state is within their own 4 eps of zero, fire with it.
std::optional<Settled> settle_step_events(std::span<const Event> events, EventWatch& watch, double t, double h,
                                          const Eigen::VectorXd& y_start, Eigen::VectorXd& y, EventLocation location,
                                          const Restep& restep, RunResult& result);

}  // namespace stepwise
