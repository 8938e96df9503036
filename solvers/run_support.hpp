// Pieces every integrator shares: RHS counting, divergence test, CPU clock, trajectory recording.
#pragma once

#include "integrator.hpp"

#include <fmt/format.h>

#include <ctime>

namespace stepwise {

// forwards to a system and counts every call of f in Stats; backends see only this wrapper.
// Jacobian evaluations are counted by the caller, analytic or finite-difference alike.
class CountedSystem final : public OdeSystem {
 public:
  CountedSystem(const OdeSystem& inner, Stats& stats) : inner_(inner), stats_(stats) {}
  int size() const override { return inner_.size(); }
  void rhs(double t, Eigen::Ref<const Eigen::VectorXd> y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    ++stats_.rhs_evals;
    inner_.rhs(t, y, dydt);
  }
  bool autonomous() const override { return inner_.autonomous(); }
  bool has_jacobian() const override { return inner_.has_jacobian(); }
  void jacobian(double t, Eigen::Ref<const Eigen::VectorXd> y, Eigen::Ref<Eigen::MatrixXd> dfdy) const override {
    inner_.jacobian(t, y, dfdy);
  }
  bool has_sparse_jacobian() const override { return inner_.has_sparse_jacobian(); }
  void sparse_jacobian(double t, Eigen::Ref<const Eigen::VectorXd> y, Eigen::SparseMatrix<double>& dfdy) const override {
    inner_.sparse_jacobian(t, y, dfdy);
  }
  std::optional<SecondOrderView> second_order() const override { return inner_.second_order(); }
  void acceleration(double t, Eigen::Ref<const Eigen::VectorXd> y, Eigen::Ref<Eigen::VectorXd> a) const override {
    ++stats_.rhs_evals;
    inner_.acceleration(t, y, a);
  }
  // not counted here: a stepper sweeping in blocks counts one evaluation per sweep itself
  bool has_local_acceleration() const override { return inner_.has_local_acceleration(); }
  void local_acceleration(double t, const double* x, const double* v, double* a, Eigen::Index first,
                          Eigen::Index count) const override {
    inner_.local_acceleration(t, x, v, a, first, count);
  }
  std::optional<WaveGridView> wave_grid() const override { return inner_.wave_grid(); }
  const MassSpringView* mass_spring() const override { return inner_.mass_spring(); }
  const ClothGridView* cloth_grid() const override { return inner_.cloth_grid(); }
  void force_jacobians(double t, Eigen::Ref<const Eigen::VectorXd> y, bool definite, Eigen::SparseMatrix<double>& dfdx,
                       Eigen::SparseMatrix<double>& dfdv) const override {
    ++stats_.jac_evals;
    inner_.force_jacobians(t, y, definite, dfdx, dfdv);
  }
  std::optional<RigidBodyView> free_rigid_body() const override { return inner_.free_rigid_body(); }
  std::optional<ContactBodiesView> contact_bodies() const override { return inner_.contact_bodies(); }
  ContactOutcome resolve_contacts(Eigen::Ref<Eigen::VectorXd> y, double dt, ContactMemory& memory) const override {
    return inner_.resolve_contacts(y, dt, memory);
  }
  std::span<const Event> events() const override { return inner_.events(); }
  bool project(Eigen::Ref<Eigen::VectorXd> y) const override {
    const bool projected = inner_.project(y);
    if (projected) ++stats_.projections;
    return projected;
  }
  double event_free_interval() const override { return inner_.event_free_interval(); }
  Stats& stats() const { return stats_; }
  // the wrapped system, for a backend's hot path that counts its calls itself
  const OdeSystem& inner() const { return inner_; }

 private:
  const OdeSystem& inner_;
  Stats& stats_;
};

// thread CPU time in seconds: sweeps run in parallel, so process time would mix runs
inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// the largest step an adaptive integrator may take on this system: the control's cap, and half the
// shortest event-free interval
inline double max_adaptive_step(const StepControl& control, const OdeSystem& system) {
  return std::min(control.max_step, 0.5 * system.event_free_interval());
}

// |y|inf above which a run has blown up: blowup * max(1, |y0|inf)
inline double divergence_bound(const StepControl& control, const Eigen::VectorXd& y0) {
  return control.blowup * std::max(1.0, y0.lpNorm<Eigen::Infinity>());
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

// an event handled at t: the state is changed by its handler and the event is recorded
inline void handle_event(RunResult& result, std::span<const Event> events, size_t index, double t, Eigen::VectorXd& y) {
  std::string kind = events[index].apply(t, y);
  if (!kind.empty()) record_event(result, t, std::move(kind), index);
}

// the state at an output time joins the trajectory (through the control's observer, if it has one)
inline void record_output(RunResult& result, const StepControl& control, double t, const Eigen::VectorXd& y) {
  result.trajectory.t.push_back(t);
  result.trajectory.y.push_back(control.observe ? control.observe(y) : y);
  result.t_stop = t;
  result.y_stop = y;
}

}  // namespace stepwise
