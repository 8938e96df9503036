// Pieces every integrator shares: RHS counting, divergence test, CPU clock, trajectory recording.
#pragma once

#include <stepwise/solvers/capabilities/mass_spring.hpp>
#include <stepwise/solvers/capabilities/second_order.hpp>
#include <stepwise/solvers/integrator.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>


namespace stepwise {

// the count of the CPU time a method's own worker threads spend for the run on the calling thread (nullptr outside
// a run): Integrator::integrate adds it to the run's cpu_seconds, so a run costs every thread it runs
std::atomic<double>* worker_cpu_seconds();

// made on each thread of a parallel region a method opens (an OpenMP team: vbd's colour sweeps, the wave's rows),
// with the count read on the calling thread before it: on a worker (not the calling thread) the thread's CPU time
// from here to the region's end is added to the count
class WorkerCpuTime {
 public:
  WorkerCpuTime(std::atomic<double>* count, bool worker) : count_(worker ? count : nullptr), start_(count_ ? thread_cpu_seconds() : 0) {}
  ~WorkerCpuTime() {
    if (count_) count_->fetch_add(thread_cpu_seconds() - start_);
  }
  WorkerCpuTime(const WorkerCpuTime&) = delete;
  WorkerCpuTime& operator=(const WorkerCpuTime&) = delete;

 private:
  std::atomic<double>* count_;
  double start_;
};

// forwards to a system and counts every call of f in Stats; backends see only this wrapper. Capabilities
// are passed through untouched (as<T>() reaches the model's), but for the projection, which this wrapper offers
// in the model's place to count it: a method that evaluates forces through one counts that call itself, with
// the helpers below. Jacobian evaluations are counted by the caller, analytic or finite-difference alike.
class CountedSystem final : public OdeSystem, public Projection {
 public:
  CountedSystem(const OdeSystem& inner, Stats& stats) : inner_(inner), stats_(stats), projection_(inner.as<Projection>()) {}
  int size() const override { return inner_.size(); }
  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    ++stats_.rhs_evals;
    inner_.rhs(t, y, dydt);
  }
  bool autonomous() const override { return inner_.autonomous(); }
  void project(Eigen::Ref<Eigen::VectorXd> y) const override {
    projection_->project(y);
    ++stats_.projections;
  }
  const void* capability(const std::type_info& type) const override {
    if (type == typeid(Projection)) return projection_ ? static_cast<const Projection*>(this) : nullptr;
    return inner_.capability(type);
  }
  Stats& stats() const { return stats_; }
  // the wrapped system, for a backend's hot path that counts its calls itself
  const OdeSystem& inner() const { return inner_; }

 private:
  const OdeSystem& inner_;
  Stats& stats_;
  const Projection* projection_;
};

// a = dv/dt of a second-order system (n entries), counted as one call of f: the model's own acceleration
// where it has one, else the second half of f, evaluated into `f` (the caller's buffer, kept between steps)
inline void second_order_acceleration(const CountedSystem& system, const SecondOrderView& view, double t,
                                      const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> a, Eigen::VectorXd& f) {
  if (view.acceleration) {
    ++system.stats().rhs_evals;
    view.acceleration(t, y, a);
    return;
  }
  f.resize(system.size());
  system.rhs(t, y, f);
  a = f.tail(view.positions);
}

// a mass-spring system's force Jacobians (MassSpringView::force_jacobians), counted as one Jacobian evaluation
inline void force_jacobians(const CountedSystem& system, const MassSpringView& view, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                            bool definite, Eigen::SparseMatrix<double>& dfdx, Eigen::SparseMatrix<double>& dfdv) {
  ++system.stats().jac_evals;
  view.force_jacobians(t, y, definite, dfdx, dfdv);
}


// the largest step an adaptive integrator may take on this system: the control's cap, and half the
// shortest event-free interval
inline double max_adaptive_step(const StepControl& control, const OdeSystem& system) {
  return std::min(control.max_step, 0.5 * event_free_interval_of(system));
}

// two times within a root's precision are one instant: an event located a hair short of an output time (a left
// root) has reached it, and no solver takes the step that is left (SUNDIALS refuses one below 2 u |t|, CV_TOO_CLOSE;
// GSL's bsimp fails on one of 1e-13 s at t = 19.5, its extrapolation lost in round-off). The precision is SUNDIALS'
// root tolerance, 100 u |t| (at least 100 u)
inline bool same_instant(double a, double b) {
  return std::abs(a - b) <= 100 * std::numeric_limits<double>::epsilon() * std::max({std::abs(a), std::abs(b), 1.0});
}

// |y|inf above which a run has blown up: blowup * max(1, |y0|inf), from y0 or its norm
inline double divergence_bound(const StepControl& control, double y0_norm) { return control.blowup * std::max(1.0, y0_norm); }
inline double divergence_bound(const StepControl& control, const Eigen::VectorXd& y0) {
  return divergence_bound(control, y0.lpNorm<Eigen::Infinity>());
}

inline bool has_diverged(const Eigen::VectorXd& y, double bound) {
  return !y.allFinite() || y.lpNorm<Eigen::Infinity>() > bound;
}

inline void mark_diverged(RunResult& result, double t) {
  result.status = Status::diverged;
  result.t_stop = t;
  result.message = fmt::format("diverged at t = {:.9g}: state non-finite or beyond the blow-up bound", t);
}

inline void mark_failed(RunResult& result, double t, std::string message) {
  result.status = Status::failed;
  result.t_stop = t;
  result.message = std::move(message);
}

// a fresh result at (t0, y0)
inline RunResult begin_run(double t0, const Eigen::VectorXd& y0) {
  RunResult result;
  result.t_stop = t0;
  result.y_stop = y0;
  return result;
}

// something happened at t (kind, as summary.json writes it) through event `index` of the system, or
// EventRecord::by_method: it joins the run's events and their count
inline void record_event(RunResult& result, double t, std::string kind, size_t index) {
  result.events.push_back({t, std::move(kind), index});
  ++result.stats.events;
}

// Zeno: one event firing zeno_firings times within zeno_span(t) of the time t (a rate above 1e6 per unit of
// time), where its handler has no rest rule to end the bouncing: a ball's impacts accumulating at t_inf, each
// flight shorter than the last until they are the solution's noise (a ball at rtol 1e-10 goes on bouncing at
// 4e-9 m/s, a firing every 1e-9 s, measured)
inline constexpr int zeno_firings = 100;
inline double zeno_span(double t) { return 1e-4 * std::max(1.0, std::abs(t)); }

// an event handled at t: the state is changed by its handler and the event is recorded (with the states just
// before and after, where the event keeps them). False when the run ends here: at a terminal event
// (result.terminated, t_stop and y_stop there) or at Zeno behaviour (failed, naming the event and the time)
[[nodiscard]] inline bool handle_event(RunResult& result, std::span<const Event> events, size_t index, double t, Eigen::VectorXd& y) {
  const Event& event = events[index];
  Eigen::VectorXd before;
  if (event.keeps_state) before = y;
  std::string kind = event.apply(t, y);
  if (kind.empty()) return true;
  record_event(result, t, std::move(kind), index);
  if (event.keeps_state) {
    result.events.back().before = std::move(before);
    result.events.back().after = y;
  }
  if (!event.surface && !event.may_rest) {
    int firings = 0;
    double first = t;
    for (auto e = result.events.rbegin(); e != result.events.rend() && e->t >= t - zeno_span(t) && firings < zeno_firings; ++e)
      if (e->event == index) ++firings, first = e->t;
    if (firings >= zeno_firings) {
      mark_failed(result, t, fmt::format("event '{}' fired {} times within {:.3g} before t = {:.9g}: Zeno behaviour, the firings "
                                         "accumulate; a `rest` rule ends the bouncing", event.name, firings, t - first, t));
      return false;
    }
  }
  if (event.terminal) {
    result.terminated = true;
    result.t_stop = t;
    result.y_stop = y;
    return false;
  }
  return true;
}

// the state at an output time joins the trajectory, or goes to the control's sink (through its observer, if it
// has one); false when the sink ended the run (it is then diverged at t, for the reason the sink gave)
[[nodiscard]] inline bool record_output(RunResult& result, const StepControl& control, double t, const Eigen::VectorXd& y) {
  result.t_stop = t;
  result.y_stop = y;
  if (!control.sink) {
    result.trajectory.t.push_back(t);
    result.trajectory.y.push_back(control.observe ? control.observe(y) : y);
    return true;
  }
  // the states just before and after each event up to t go first, in time order
  for (; control.sink_events && result.events_written < result.events.size() && result.events[result.events_written].t <= t; ++result.events_written) {
    const EventRecord& e = result.events[result.events_written];
    if (!opens_instant(result.events, result.events_written)) continue;
    for (const Eigen::VectorXd* state : {&e.before, &e.after})
      if (const std::string stop = control.sink(e.t, control.observe ? control.observe(*state) : *state); !stop.empty()) {
        result.status = Status::diverged;
        result.message = fmt::format("diverged at t = {:.9g}: {}", e.t, stop);
        return false;
      }
  }
  if (const std::string stop = control.sink(t, control.observe ? control.observe(y) : y); !stop.empty()) {
    result.status = Status::diverged;
    result.message = fmt::format("diverged at t = {:.9g}: {}", t, stop);
    return false;
  }
  return true;
}

}  // namespace stepwise
