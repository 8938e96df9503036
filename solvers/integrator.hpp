// What a run is and what it returns: the step control, the counters, the result, and the Integrator interface
// every method is made as (method.hpp registers methods; method_table.hpp makes one by name).
#pragma once

#include <stepwise/solvers/memory_budget.hpp>
#include <stepwise/solvers/ode_system.hpp>

#include <functional>
#include <tuple>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace stepwise {

// where an event found between two step ends is placed: on the straight segment between the two states
// (the seeds' method: g interpolated linearly), or by re-stepping from the step's start to the root of g
enum class EventLocation { linear, restep };

// how a run is stepped: a fixed dt, or adaptively to rtol/atol
struct StepControl {
  std::optional<double> dt;                                   // fixed step (s); empty: adaptive
  double rtol = 1e-6;                                         // relative tolerance (adaptive)
  double atol = 1e-9;                                         // absolute tolerance (adaptive)
  double max_step = std::numeric_limits<double>::infinity();  // cap on an adaptive step (s)
  double blowup = 1e12;  // a state with |y|inf > blowup * max(1, |y0|inf) has diverged
  long max_steps = 5'000'000;  // an adaptive run taking more steps (CVODE: between two outputs) fails
  EventLocation event_location = EventLocation::linear;  // hand-written and GSL steppers; CVODE finds roots itself
  // the method's own settings by name (its options, declared with it: solvers/method.hpp's MethodOption, which holds
  // each one's range and default; a choice as its index), as the caller gives them; a method reads each through its
  // registration (Method::setting), and check_step_control refuses one it does not declare or out of its range
  std::map<std::string, double, std::less<>> settings;
  // what the trajectory keeps at each output time: the whole state when empty, or a summary of it (a
  // particle system's energy and centroid rather than every particle)
  std::function<Eigen::VectorXd(const Eigen::VectorXd& y)> observe;
  // where the samples go when set, instead of the trajectory (a long run's rows streamed to their file, not
  // held): called with each output time and sample; a non-empty return ends the run diverged there, for that
  // reason (the sample's energy overflowed)
  std::function<std::string(double t, const Eigen::VectorXd& sample)> sink;
  // the trajectory holds every accepted step's end (SciPy's solve_ivp without t_eval) besides the output times
  bool record_steps = false;
  // the sink also gets the states just before and after each event that keeps them (trajectory.csv's rows)
  bool sink_events = true;

  static StepControl fixed(double dt) {
    StepControl c;
    c.dt = dt;
    return c;
  }
  static StepControl adaptive(double rtol, double atol) {
    StepControl c;
    c.rtol = rtol;
    c.atol = atol;
    return c;
  }
};

struct Stats {
  long steps = 0;           // accepted steps
  long rejected = 0;        // steps rejected by error or convergence tests
  long rhs_evals = 0;       // calls of f, counted in the wrapper (finite-difference Jacobians included)
  long jac_evals = 0;       // analytic or finite-difference Jacobian evaluations
  long linear_solves = 0;   // solves with a factorised Newton matrix
  long factorizations = 0;  // factorisations of a Newton matrix
  long events = 0;          // events handled
  long projections = 0;     // projections onto the system's manifold (the Projection capability)
  long contact_sweeps = 0;  // Gauss-Seidel sweeps over contacts (solvers/contact_solve.hpp)
  long newton_iterations = 0;     // Newton iterations on an incremental potential (implicit-euler-newton)
  long line_search_halvings = 0;  // their line searches' halvings
  long colours = 0;               // the node colours a per-vertex solver sweeps (vbd)
  double potential_decrease = 0;  // how far its sweeps lowered the incremental potential over the run (J)
  double cpu_seconds = 0;   // thread CPU time of the integration
  // the members, to copy a result between processes (report/pack.hpp)
  static auto fields(auto& s) {
    return std::tie(s.steps, s.rejected, s.rhs_evals, s.jac_evals, s.linear_solves, s.factorizations, s.events, s.projections, s.contact_sweeps,
                    s.newton_iterations, s.line_search_halvings, s.colours, s.potential_decrease, s.cpu_seconds);
  }
};

enum class Status { ok, diverged, failed };
std::string_view to_string(Status status);

// state at each requested output time; a run that stops early ends its trajectory there
struct Trajectory {
  std::vector<double> t;
  std::vector<Eigen::VectorXd> y;
  static auto fields(auto& s) { return std::tie(s.t, s.y); }
};

struct EventRecord {
  double t = 0;
  std::string kind;  // what the handler reported ("impact", "rest")
  size_t event = 0;  // which of the system's events; none of them (by_method) for what the method handled
                     // itself (a contact method's impacts)
  static constexpr size_t by_method = static_cast<size_t>(-1);
  // for an event that keeps them, the state just before its instant and just after all of the instant's handlers
  // (the same for every event firing at that instant: a state between two handlers is none the system was in)
  Eigen::VectorXd before, after;
  static auto fields(auto& s) { return std::tie(s.t, s.kind, s.event, s.before, s.after); }
};

// whether events[k] keeps its states and is the first to do so at its instant: the one whose states a trajectory
// shows (the others of the instant hold the same two)
inline bool opens_instant(const std::vector<EventRecord>& events, size_t k) {
  if (events[k].before.size() == 0) return false;
  for (size_t j = k; j-- > 0 && events[j].t == events[k].t;)
    if (events[j].before.size() > 0) return !(events[j].before == events[k].before);
  return true;
}

struct RunResult {
  Status status = Status::ok;
  std::string message;   // empty when ok; names the time (diverged) or the backend call and its code (failed)
  double t_stop = 0;     // time the run ended: the last output time, or when it diverged or failed
  Eigen::VectorXd y_stop;  // last finite state
  Trajectory trajectory;
  Stats stats;
  std::vector<EventRecord> events;
  bool terminated = false;  // ended ok at a terminal event (t_stop), before the last output time
  size_t events_written = 0;  // events whose states went to the control's sink (record_output)
  static auto fields(auto& s) { return std::tie(s.status, s.message, s.t_stop, s.y_stop, s.trajectory, s.stats, s.events, s.terminated); }
};

// thread CPU time in seconds: sweeps run in parallel, so process time would mix runs (a run's cpu_seconds is its
// thread's and its method's own workers', solvers/run_support.hpp: WorkerCpuTime)
double thread_cpu_seconds();

class Integrator {
 public:
  virtual ~Integrator() = default;
  // integrate from (t0, y0) through the increasing output times t_out (each > t0), timed: stats.cpu_seconds
  // is the thread CPU time of the call
  RunResult integrate(const OdeSystem& system, double t0, const Eigen::VectorXd& y0, std::span<const double> t_out) const;
  // the same, untimed: a read of the thread CPU clock is a system call (0.38 us measured here, against
  // 1-2 us for a whole small run), so a benchmark that times the call itself calls this
  virtual RunResult solve(const OdeSystem& system, double t0, const Eigen::VectorXd& y0, std::span<const double> t_out) const = 0;
};

}  // namespace stepwise
