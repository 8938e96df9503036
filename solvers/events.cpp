#include "events.hpp"

#include "run_support.hpp"

#include <cmath>
#include <limits>

namespace stepwise {
namespace {

// whether g going from a to b crosses zero in the direction (+1 rising, -1 falling, 0 either): strictly from
// one side, to zero or the other (so never from g = 0: an event at t0, or one just handled)
bool crosses(double a, double b, int direction) {
  const bool falling = a > 0 && b <= 0, rising = a < 0 && b >= 0;
  return direction < 0 ? falling : direction > 0 ? rising : falling || rising;
}

// a built-in surface event's crossing: which event, and where in the step the linear interpolant of its g
// vanishes, in [0, 1]: 1 when g starts at zero (a flight shorter than the step left the surface and came
// back), 0 when the state is already behind the surface
struct SurfaceCrossing {
  size_t index;
  double fraction;
};

std::optional<SurfaceCrossing> first_surface_crossing(std::span<const Event> events, const Eigen::VectorXd& g0, const Eigen::VectorXd& g1) {
  std::optional<SurfaceCrossing> first;
  for (size_t i = 0; i < events.size(); ++i) {
    if (!events[i].surface) continue;
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
    if (!first || s < first->fraction) first = SurfaceCrossing{i, s};
  }
  return first;
}

// the root in [s_lo, s_hi] of a function of the step's fraction whose values at the ends differ in sign, by
// the Illinois variant of regula falsi, each value on the re-stepped state; a re-step that fails ends the
// search. Ends with y at the root. (Newton steps on an event's rate along the solution were tried: about
// 6 values a root instead of 8, but each with the rate evaluated too, so no fewer instructions on the ball)
double refine(double s_lo, double s_hi, double f_lo, double f_hi, Eigen::VectorXd& y, const Restep& restep,
              const std::function<double(double s, const Eigen::VectorXd& y)>& value, double s_tolerance) {
  double s = s_hi;
  int side = 0;  // which end was kept last time, to halve its value (Illinois)
  const double scale = std::max(std::abs(f_lo), std::abs(f_hi));
  for (int iteration = 0; iteration < 100; ++iteration) {
    s = f_hi == f_lo ? 0.5 * (s_lo + s_hi) : (s_lo * f_hi - s_hi * f_lo) / (f_hi - f_lo);
    if (!(s >= s_lo && s <= s_hi)) s = 0.5 * (s_lo + s_hi);  // a non-finite value: bisect
    if (!restep(s, y)) break;
    const double f = value(s, y);
    if (std::abs(f) <= 4 * std::numeric_limits<double>::epsilon() * scale || s_hi - s_lo <= s_tolerance) break;
    if ((f > 0) == (f_lo > 0)) {
      s_lo = s;
      f_lo = f;
      if (side == -1) f_hi /= 2;
      side = -1;
    } else {
      s_hi = s;
      f_hi = f;
      if (side == 1) f_lo /= 2;
      side = 1;
    }
  }
  return s;
}

// the seeds' location of a surface event: the linear estimate, carried there by a re-step, then refined
std::pair<double, Eigen::VectorXd> locate_surface(const Event& event, const SurfaceCrossing& crossing, double t, double h,
                                                  const Eigen::VectorXd& y0, const Eigen::VectorXd& y1, EventLocation location,
                                                  const Restep& restep) {
  const double s = crossing.fraction;
  if (s == 1) return {t + h, y1};
  if (s == 0) return {t, y0};
  // the whole state is carried to the estimated time by a step of h s from the step's start: interpolating
  // it on the segment instead would cut through the parabola of every other particle in flight, and one
  // that left a surface and came back within the step would be put behind it
  Eigen::VectorXd y = y0 + s * (y1 - y0);
  if (!restep(s, y)) y = y0 + s * (y1 - y0);
  // g starting at zero gives no bracket to refine
  if (location == EventLocation::linear || event.g(t, y0) == 0) return {t + s * h, y};
  const double root = refine(0, 1, event.g(t, y0), event.g(t + h, y1), y, restep,
                             [&](double f, const Eigen::VectorXd& ys) { return event.g(t + f * h, ys); }, 1e-15);
  return {t + root * h, y};
}

// a user's event inside the step: the bracket [s_lo, s_hi] where its g crosses zero in its direction, found
// from the ends or, where g's rate changes sign between them, from the extremum between
struct Bracket {
  double s_lo, s_hi, g_lo, g_hi;
};
// `fired_rate`: where the event was just handled (the step starts on its level), its g's rate just before the
// handler; else nullopt
std::optional<Bracket> sign_change_bracket(const Event& event, std::optional<double> fired_rate, double zero, double t, double h, double a,
                                           double b, const Eigen::VectorXd& y0, const Eigen::VectorXd& y1, const Restep& restep) {
  const int d = event.direction;
  if (crosses(a, b, d)) return Bracket{0, 1, a, b};
  // from one side to the other in the wrong direction, or without a rate: nothing (the rates are not evaluated)
  if (!event.rate || b == 0 || (!fired_rate && (a > 0) != (b > 0))) return std::nullopt;
  const double r0 = event.rate(t, y0), r1 = event.rate(t + h, y1);
  // the extremum between the ends, and g there
  const auto extremum = [&] {
    Eigen::VectorXd y = y0;
    const double s = refine(0, 1, r0, r1, y, restep, [&](double f, const Eigen::VectorXd& ys) { return event.rate(t + f * h, ys); }, 1e-12);
    double g = event.g(t + s * h, y) - zero;
    // within rounding of zero at its extremum: a touch (a double root), which reaches the level
    if (std::abs(g) <= 4 * std::numeric_limits<double>::epsilon() * std::max(std::abs(a), std::abs(b))) g = 0;
    return std::pair{s, g};
  };
  // a pair of roots needs an extremum on the other side of zero from b: a minimum where b > 0, a maximum where
  // b < 0; it is there when the rate goes from toward zero to away from it
  const bool toward = b > 0 ? (r0 < 0 && r1 > 0) : (r0 > 0 && r1 < 0);
  if (fired_rate) {
    // just handled, on its level. Where its handler turned the motion back (a bounce) or stopped it, and the
    // step ends on the side it came from, it came back through the level: after the extremum, or at once where
    // the flight is below what the solution resolves (its noise, a rebound of 1e-15 m/s): so a Zeno ball's
    // firings pile up and are caught, rather than one lost in the noise letting it through the floor. Where the
    // handler let it go on (an event that only counts), that is no crossing
    const double toward_far = d != 0 ? d : (*fired_rate > 0 ? 1.0 : -1.0);
    const bool turned = !(r0 * *fired_rate > 0), far = b * toward_far > 0;
    if (turned && far) {
      if (!toward) return Bracket{0, 0, 0, 0};
      const auto [s_star, g_star] = extremum();
      return crosses(g_star, b, d) ? Bracket{s_star, 1, g_star, b} : Bracket{s_star, s_star, 0, 0};
    }
    // it left the level (or went on past it): a crossing back needs the extremum beyond it
    if (!toward) return std::nullopt;
    const auto [s_star, g_star] = extremum();
    if (crosses(g_star, b, d)) return Bracket{s_star, 1, g_star, b};
    return std::nullopt;
  }
  if (!toward) return std::nullopt;
  const auto [s_star, g_star] = extremum();
  if (crosses(a, g_star, d)) return Bracket{0, s_star, a, g_star};
  if (crosses(g_star, b, d)) return Bracket{s_star, 1, g_star, b};
  return std::nullopt;
}

}  // namespace


EventWatch start_watch(std::span<const Event> events, double t, const Eigen::VectorXd& y) {
  EventWatch watch;
  event_values(events, t, y, watch.g);
  watch.zero = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(events.size()));
  return watch;
}

void event_values(std::span<const Event> events, double t, const Eigen::VectorXd& y, Eigen::VectorXd& g) {
  g.resize(static_cast<Eigen::Index>(events.size()));
  for (size_t i = 0; i < events.size(); ++i) g[static_cast<Eigen::Index>(i)] = events[i].g(t, y);
}

std::optional<Settled> settle_step_events(std::span<const Event> events, EventWatch& watch, double t, double h,
                                          const Eigen::VectorXd& y_start, Eigen::VectorXd& y, EventLocation location,
                                          const Restep& restep, RunResult& result) {
  if (events.empty() || !(h > 0)) return std::nullopt;
  Eigen::VectorXd& g_end = watch.g_end;
  event_values(events, t + h, y, g_end);
  // the earliest event of the step: each candidate located, the one at the earliest time kept
  std::optional<size_t> first;
  double t_first = 0;
  Eigen::VectorXd y_first;
  const Eigen::VectorXd& g_start = watch.g;
  if (const auto surface = first_surface_crossing(events, g_start, g_end)) {
    std::tie(t_first, y_first) = locate_surface(events[surface->index], *surface, t, h, y_start, y, location, restep);
    first = surface->index;
  }
  for (size_t i = 0; i < events.size(); ++i) {
    if (events[i].surface) continue;
    const auto k = static_cast<Eigen::Index>(i);
    const double zero = watch.zero[k];
    const auto bracket = sign_change_bracket(events[i], watch.fired == i ? std::optional(watch.fired_rate) : std::nullopt, zero, t, h,
                                             g_start[k] - zero, g_end[k] - zero, y_start, y, restep);
    if (!bracket) continue;
    Eigen::VectorXd ys = y;
    const double s = refine(bracket->s_lo, bracket->s_hi, bracket->g_lo, bracket->g_hi, ys, restep,
                            [&](double f, const Eigen::VectorXd& state) { return events[i].g(t + f * h, state) - zero; }, 1e-15);
    if (!first || t + s * h < t_first) {
      first = i;
      t_first = t + s * h;
      y_first = std::move(ys);
    }
  }
  watch.zero.setZero();
  watch.fired.reset();
  if (!first) {
    watch.g.swap(g_end);
    return std::nullopt;
  }
  const double rate_before = events[*first].rate ? events[*first].rate(t_first, y_first) : 0.0;
  const bool go_on = handle_event(result, events, *first, t_first, y_first);
  y = std::move(y_first);
  event_values(events, t_first, y, watch.g);
  // an event just handled sits on its zero: rounding may leave its g a hair behind, and the next step would see
  // the same crossing again. A built-in undirected event's g is taken as 0; a user's event measures its next
  // crossing from where its g is now
  const auto k = static_cast<Eigen::Index>(*first);
  if (!events[*first].surface) {
    watch.zero[k] = watch.g[k];
    watch.fired = *first;
    watch.fired_rate = rate_before;
  }
  else if (events[*first].direction == 0) watch.g[k] = 0;
  return Settled{t_first, go_on};
}

}  // namespace stepwise
