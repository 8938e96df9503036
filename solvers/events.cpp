#include "events.hpp"

#include "run_support.hpp"

#include <cmath>
#include <limits>

namespace stepwise {

Eigen::VectorXd event_values(std::span<const Event> events, double t, const Eigen::VectorXd& y) {
  Eigen::VectorXd g(static_cast<Eigen::Index>(events.size()));
  for (size_t i = 0; i < events.size(); ++i) g[static_cast<Eigen::Index>(i)] = events[i].g(t, y);
  return g;
}

std::optional<Crossing> first_crossing(std::span<const Event> events, const Eigen::VectorXd& g0, const Eigen::VectorXd& g1) {
  std::optional<Crossing> first;
  for (size_t i = 0; i < events.size(); ++i) {
    const int d = events[i].direction;
    // signs as for a falling event; a rising one is the same with g negated
    const double sign = d > 0 ? -1.0 : 1.0;
    const double a = sign * g0[static_cast<Eigen::Index>(i)], b = sign * g1[static_cast<Eigen::Index>(i)];
    double s = 0;
    if (d == 0) {
      // either way through zero
      if (!((a > 0 && b <= 0) || (a < 0 && b >= 0))) continue;
      s = a / (a - b);
    } else {
      // a directed event is a surface the state may not end a step behind (a wall, the ground):
      // - from the front to or behind it: the crossing of the segment;
      // - from on it (just after an event) to behind it: it left and came back within the step, a flight
      //   shorter than the step, and the segment cannot say when: the step's end;
      // - already behind it (carried there by a step to another event): at once, at the step's start.
      // A state resting on the surface (g = 0 at both ends) does not cross it.
      if (!(b < 0 || (a > 0 && b == 0))) continue;
      s = a > 0 ? a / (a - b) : a == 0 ? 1.0 : 0.0;
    }
    if (!first || s < first->fraction) first = Crossing{i, s};
  }
  return first;
}

std::pair<double, Eigen::VectorXd> locate_event(const Event& event, const Crossing& crossing, double t, double h,
                                                const Eigen::VectorXd& y0, const Eigen::VectorXd& y1,
                                                EventLocation location, const Restep& restep) {
  double s = crossing.fraction;
  if (s == 1) return {t + h, y1};
  if (s == 0) return {t, y0};
  // the whole state is carried to the estimated time by a step of h s from the step's start: interpolating
  // it on the segment instead would cut through the parabola of every other particle in flight, and one
  // that left a surface and came back within the step would be put behind it
  Eigen::VectorXd y = y0 + s * (y1 - y0);
  if (!restep(s, y)) y = y0 + s * (y1 - y0);
  // g starting at zero gives no bracket to refine
  if (location == EventLocation::linear || event.g(t, y0) == 0) return {t + s * h, y};

  // Illinois regula falsi on g(s) over the bracket [0, 1] of the step
  double s_lo = 0, s_hi = 1;
  double g_lo = event.g(t, y0), g_hi = event.g(t + h, y1);
  int side = 0;  // which end was kept last time, to halve its g (Illinois)
  const double scale = std::max(std::abs(g_lo), std::abs(g_hi));
  for (int iteration = 0; iteration < 60; ++iteration) {
    s = (s_lo * g_hi - s_hi * g_lo) / (g_hi - g_lo);
    if (!restep(s, y)) break;
    const double g = event.g(t + s * h, y);
    if (std::abs(g) <= 4 * std::numeric_limits<double>::epsilon() * scale || s_hi - s_lo <= 1e-15) break;
    if ((g > 0) == (g_lo > 0)) {
      s_lo = s;
      g_lo = g;
      if (side == -1) g_hi /= 2;
      side = -1;
    } else {
      s_hi = s;
      g_hi = g;
      if (side == 1) g_lo /= 2;
      side = 1;
    }
  }
  return {t + s * h, y};
}

std::optional<double> settle_step_events(std::span<const Event> events, Eigen::VectorXd& g_start, double t, double h,
                                         const Eigen::VectorXd& y_start, Eigen::VectorXd& y, EventLocation location,
                                         const Restep& restep, RunResult& result) {
  if (events.empty()) return std::nullopt;
  Eigen::VectorXd g_end = event_values(events, t + h, y);
  const auto crossing = first_crossing(events, g_start, g_end);
  if (!crossing) {
    g_start = std::move(g_end);
    return std::nullopt;
  }
  auto [t_event, y_event] = locate_event(events[crossing->index], *crossing, t, h, y_start, y, location, restep);
  handle_event(result, events, crossing->index, t_event, y_event);
  y = std::move(y_event);
  g_start = event_values(events, t_event, y);
  // an undirected event just handled (a drop at a given time) sits on its zero: rounding may leave its g a
  // hair behind, and the next step would see the same crossing again
  if (events[crossing->index].direction == 0) g_start[static_cast<Eigen::Index>(crossing->index)] = 0;
  return t_event;
}

}  // namespace stepwise
