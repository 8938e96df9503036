// Events between two step ends: detection by the sign of g, and location on the step.
//
// The seeds' method (collision of a particle with a plane): when the signed distance g changes sign over
// a step, the crossing time is estimated on the segment p(t) -> p(t + h), where the linear interpolant of g
// vanishes, s = g0 / (g0 - g1), and the state is carried there by one step of h s from the step's start
// (the model's handler then moves the particle onto the surface). The refinement repeats such steps,
// s found by the Illinois variant of regula falsi on g, until g is zero to round-off.
#pragma once

#include "integrator.hpp"

#include <functional>
#include <optional>

namespace stepwise {

// g_i(t, y) for every event
Eigen::VectorXd event_values(std::span<const Event> events, double t, const Eigen::VectorXd& y);

struct Crossing {
  size_t index;     // which event
  double fraction;  // where in the step the linear interpolant of its g vanishes, in [0, 1]: 1 when g
                    // starts at zero (a flight shorter than the step left the surface and came back), 0
                    // when the state is already behind the surface of a directed event
};

// the earliest event whose g crosses zero in its direction between g0 (step start) and g1 (step end)
std::optional<Crossing> first_crossing(std::span<const Event> events, const Eigen::VectorXd& g0, const Eigen::VectorXd& g1);

// recomputes the state at fraction s of the step from its start; false when the step fails
using Restep = std::function<bool(double s, Eigen::VectorXd& y)>;

// the time and state of the crossing in the step (t, y0) -> (t + h, y1)
std::pair<double, Eigen::VectorXd> locate_event(const Event& event, const Crossing& crossing, double t, double h,
                                                const Eigen::VectorXd& y0, const Eigen::VectorXd& y1,
                                                EventLocation location, const Restep& restep);

// After a step (t, y_start) -> (t + h, y): if an event fired inside it, carry y to it, apply its handler
// (recording what happened in result) and return the event's time; either way g_start becomes g at the
// new end of the step. The one event pass of every integrator that steps by itself (fixed-step, GSL).
std::optional<double> settle_step_events(std::span<const Event> events, Eigen::VectorXd& g_start, double t, double h,
                                         const Eigen::VectorXd& y_start, Eigen::VectorXd& y, EventLocation location,
                                         const Restep& restep, RunResult& result);

}  // namespace stepwise
