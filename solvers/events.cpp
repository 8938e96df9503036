#include "events.hpp"

#include "run_support.hpp"

#include <algorithm>
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

// where in the step the linear interpolant of a built-in surface event's g vanishes, from a to b, or nullopt
// where it does not cross
std::optional<double> surface_fraction(int direction, double g0, double g1) {
  // signs as for a falling event; a rising one is the same with g negated
  const double sign = direction > 0 ? -1.0 : 1.0;
  const double a = sign * g0, b = sign * g1;
  if (direction == 0) {
    // either way through zero
    if (!((a > 0 && b <= 0) || (a < 0 && b >= 0))) return std::nullopt;
    return a / (a - b);
  }
  // a directed event is a surface the state may not end a step behind (a wall, the ground):
  // - from the front to or behind it: the crossing of the segment;
  // - from on it (just after an event) to behind it: it left and came back within the step, a flight
  //   shorter than the step, and the segment cannot say when: the step's end;
  // - already behind it (carried there by a step to another event): at once, at the step's start.
  // A state resting on the surface (g = 0 at both ends) does not cross it.
  if (!(b < 0 || (a > 0 && b == 0))) return std::nullopt;
  return a > 0 ? a / (a - b) : a == 0 ? 1.0 : 0.0;
}

std::optional<SurfaceCrossing> first_surface_crossing(std::span<const Event> events, const Eigen::VectorXd& g0, const Eigen::VectorXd& g1) {
  std::optional<SurfaceCrossing> first;
  for (size_t i = 0; i < events.size(); ++i) {
    if (!events[i].surface) continue;
    const auto k = static_cast<Eigen::Index>(i);
    const auto s = surface_fraction(events[i].direction, g0[k], g1[k]);
    if (s && (!first || *s < first->fraction)) first = SurfaceCrossing{i, *s};
  }
  return first;
}

// where a root search ends: anywhere within its tolerance of the root (`near`), or on the side the function came
// from, f_lo's sign or zero (`left`: a left root, DifferentialEquations.jl's default LeftRootFind), so that the state
// there has not crossed yet and the crossing an event's action starts from is never a new one
enum class RootSide { near, left };

// the root in [s_lo, s_hi] of a function of the step's fraction whose values at the ends differ in sign, by
// the Illinois variant of regula falsi, each value on the re-stepped state; a re-step that fails ends the
// search. Ends with y at the root (on its side, `side`). (Newton steps on an event's rate along the solution were
// tried: about 6 values a root instead of 8, but each with the rate evaluated too, so no fewer instructions on
// the ball)
double refine(double s_lo, double s_hi, double f_lo, double f_hi, Eigen::VectorXd& y, const Restep& restep,
              const std::function<double(double s, const Eigen::VectorXd& y)>& value, double s_tolerance, RootSide side = RootSide::near) {
  double s = s_hi;
  int kept = 0;  // which end was kept last time, to halve its value (Illinois)
  bool crossed = false;  // the last value is past the root (the far side of zero)
  const double scale = std::max(std::abs(f_lo), std::abs(f_hi));
  for (int iteration = 0; iteration < 100; ++iteration) {
    s = f_hi == f_lo ? 0.5 * (s_lo + s_hi) : (s_lo * f_hi - s_hi * f_lo) / (f_hi - f_lo);
    if (!(s >= s_lo && s <= s_hi)) s = 0.5 * (s_lo + s_hi);  // a non-finite value: bisect
    if (!restep(s, y)) return s;
    const double f = value(s, y);
    crossed = f != 0 && (f > 0) != (f_lo > 0);
    const bool close = std::abs(f) <= 4 * std::numeric_limits<double>::epsilon() * scale && !(side == RootSide::left && crossed);
    if (close || s_hi - s_lo <= s_tolerance) break;
    if (!crossed) {
      s_lo = s;
      f_lo = f;
      if (kept == -1) f_hi /= 2;
      kept = -1;
    } else {
      s_hi = s;
      f_hi = f;
      if (kept == 1) f_lo /= 2;
      kept = 1;
    }
  }
  // a left root: back to the bracket's near end, within the tolerance of the root, where the value has not crossed
  if (side == RootSide::left && crossed && restep(s_lo, y)) return s_lo;
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
// handler; else null
std::optional<Bracket> sign_change_bracket(const Event& event, const double* fired_rate, double zero, double t, double h, double a,
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

// an event found inside the step: which, when, the state there, and the size of its g over its bracket (the
// scale its root's precision is relative to)
struct Located {
  size_t index;
  double t;
  Eigen::VectorXd y;
  double scale;
};

// detect and locate: the earliest built-in surface crossing (the seeds' linear estimate, refined) with every other
// surface crossing at the same fraction, and each user's event crossing in its direction, on its own bracket
std::vector<Located> locate_events(std::span<const Event> events, const EventWatch& watch, double t, double h, const Eigen::VectorXd& y_start,
                                   const Eigen::VectorXd& y, EventLocation location, const Restep& restep) {
  std::vector<Located> found;
  const Eigen::VectorXd &g_start = watch.g, &g_end = watch.g_end;
  if (const auto surface = first_surface_crossing(events, g_start, g_end)) {
    auto [t_hit, y_hit] = locate_surface(events[surface->index], *surface, t, h, y_start, y, location, restep);
    for (size_t i = 0; i < events.size(); ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      if (!events[i].surface) continue;
      const auto s = surface_fraction(events[i].direction, g_start[k], g_end[k]);
      if (s && *s - surface->fraction <= 4 * std::numeric_limits<double>::epsilon()) found.push_back({i, t_hit, y_hit, 0.0});
    }
  }
  for (size_t i = 0; i < events.size(); ++i) {
    if (events[i].surface) continue;
    const auto k = static_cast<Eigen::Index>(i);
    const double zero = watch.zero[k];
    const double* fired_rate = watch.fired[i] ? &watch.fired_rate[k] : nullptr;
    const auto bracket = sign_change_bracket(events[i], fired_rate, zero, t, h, g_start[k] - zero, g_end[k] - zero, y_start, y, restep);
    if (!bracket) continue;
    Eigen::VectorXd ys = y;
    const double s = refine(bracket->s_lo, bracket->s_hi, bracket->g_lo, bracket->g_hi, ys, restep,
                            [&](double f, const Eigen::VectorXd& state) { return events[i].g(t + f * h, state) - zero; }, 1e-15,
                            RootSide::left);
    found.push_back({i, t + s * h, std::move(ys), std::max(std::abs(bracket->g_lo), std::abs(bracket->g_hi))});
  }
  return found;
}

// the instant: the earliest located event (on a tie, the one declared first), and the events that reach zero there
// (One instant, events.hpp), in the order the system declares them
std::pair<size_t, std::vector<size_t>> first_instant(std::span<const Event> events, const std::vector<Located>& found, const EventWatch& watch,
                                                     double t, double h) {
  size_t first = 0;
  for (size_t c = 1; c < found.size(); ++c)
    if (found[c].t < found[first].t || (found[c].t == found[first].t && found[c].index < found[first].index)) first = c;
  const double eps = std::numeric_limits<double>::epsilon();
  const Located& at = found[first];
  const double apart = 2e-15 * h + 2 * eps * std::max(std::abs(t), std::abs(t + h));
  std::vector<size_t> indices;
  for (const Located& c : found) {
    bool there = c.t - at.t <= apart;
    if (!there && !events[c.index].surface) {
      const double g = events[c.index].g(at.t, at.y) - watch.zero[static_cast<Eigen::Index>(c.index)];
      there = std::abs(g) <= 4 * eps * c.scale;
    }
    if (there) indices.push_back(c.index);
  }
  std::sort(indices.begin(), indices.end());
  return {first, std::move(indices)};
}

// re-arm after the handlers: an event just handled sits on its zero, and rounding may leave its g a hair behind, so
// that the next step would see the same crossing again. A built-in undirected event's g is taken as 0; a user's
// event measures its next crossing from where its g is now, and remembers its rate at the instant
void rearm(std::span<const Event> events, EventWatch& watch, std::span<const size_t> fired, const Eigen::VectorXd& rates, double t,
           const Eigen::VectorXd& y) {
  event_values(events, t, y, watch.g);
  for (const size_t i : fired) {
    const auto k = static_cast<Eigen::Index>(i);
    if (!events[i].surface) {
      watch.zero[k] = watch.g[k];
      watch.fired[i] = 1;
      watch.fired_rate[k] = rates[k];
    } else if (events[i].direction == 0) {
      watch.g[k] = 0;
    }
  }
}

}  // namespace


EventWatch start_watch(std::span<const Event> events, double t, const Eigen::VectorXd& y) {
  EventWatch watch;
  event_values(events, t, y, watch.g);
  watch.zero = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(events.size()));
  watch.fired.assign(events.size(), 0);
  watch.fired_rate = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(events.size()));
  return watch;
}

void event_values(std::span<const Event> events, double t, const Eigen::VectorXd& y, Eigen::VectorXd& g) {
  g.resize(static_cast<Eigen::Index>(events.size()));
  for (size_t i = 0; i < events.size(); ++i) g[static_cast<Eigen::Index>(i)] = events[i].g(t, y);
}

std::string not_finite_event(const Event& event, double g, double t) {
  return fmt::format("event '{}' is not finite ({}) at t = {:.9g}: its formula left its domain", event.name, g, t);
}

bool handle_events(RunResult& result, std::span<const Event> events, std::span<const size_t> indices, double t, Eigen::VectorXd& y) {
  bool go_on = true;
  const size_t first = result.events.size();
  const Eigen::VectorXd before = indices.size() > 1 ? y : Eigen::VectorXd();
  for (const size_t index : indices) {
    go_on = handle_event(result, events, index, t, y) && go_on;
    if (result.status != Status::ok) return false;
  }
  // each kept record of the instant: the state before it and after all of its handlers
  if (indices.size() > 1)
    for (size_t k = first; k < result.events.size(); ++k)
      if (result.events[k].before.size() > 0) {
        result.events[k].before = before;
        result.events[k].after = y;
      }
  if (result.terminated) result.y_stop = y;
  return go_on;
}

std::optional<Settled> settle_step_events(std::span<const Event> events, EventWatch& watch, double t, double h,
                                          const Eigen::VectorXd& y_start, Eigen::VectorXd& y, EventLocation location,
                                          const Restep& restep, RunResult& result) {
  if (events.empty() || !(h > 0)) return std::nullopt;
  event_values(events, t + h, y, watch.g_end);
  for (size_t i = 0; i < events.size(); ++i)
    if (const double g = watch.g_end[static_cast<Eigen::Index>(i)]; !std::isfinite(g)) {
      mark_failed(result, t + h, not_finite_event(events[i], g, t + h));
      return Settled{t + h, false};
    }
  std::vector<Located> found = locate_events(events, watch, t, h, y_start, y, location, restep);
  const auto disarm = [&] {
    watch.zero.setZero();
    std::fill(watch.fired.begin(), watch.fired.end(), 0);
  };
  if (found.empty()) {
    disarm();
    watch.g.swap(watch.g_end);
    return std::nullopt;
  }
  const auto [first, fired] = first_instant(events, found, watch, t, h);
  disarm();
  const double t_event = found[first].t;
  y = std::move(found[first].y);
  // each user's event's rate as the state arrives at the instant, before any handler
  Eigen::VectorXd rates = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(events.size()));
  for (const size_t i : fired)
    if (!events[i].surface && events[i].rate) rates[static_cast<Eigen::Index>(i)] = events[i].rate(t_event, y);
  const bool go_on = handle_events(result, events, fired, t_event, y);
  rearm(events, watch, fired, rates, t_event, y);
  return Settled{t_event, go_on};
}

}  // namespace stepwise
