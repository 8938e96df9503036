// Run a model with a method and measure it against its exact solution: the one path shared by
// `stepwise run`, the studies and the tests.
#pragma once

#include <stepwise/models/model.hpp>
#include <stepwise/solvers/method_table.hpp>

#include <optional>
#include <tuple>
#include <vector>

namespace stepwise {

struct Measured {
  std::vector<double> t_out;     // requested output times (t0 excluded)
  RunResult result;
  std::optional<double> error;   // max-norm error against the exact solution at t_end; empty if none or not ok
  static auto fields(auto& s) { return std::tie(s.t_out, s.result, s.error); }
};

// output times t0 + k * output_dt up to t_end, t_end always last
std::vector<double> output_times(double t_end, double output_dt);

// the run's whole state (not the model's summary of it) at t = 0 and every `interval` to t_end, for drawing:
// the pictures' frames and trail samples, the side-by-side videos' panels. A run that stopped early has fewer
// (`result` says why); t_end = 0 is the initial state alone, nothing run
struct StateSamples {
  std::vector<double> t;
  std::vector<Eigen::VectorXd> y;
  RunResult result;  // its trajectory moved into t and y
};
StateSamples sample_states(const Model& model, std::string_view method, StepControl control, double t_end, double interval);

// integrate model from its initial state at t = 0 to t_end, sampling every output_dt
Measured run_and_measure(const Model& model, std::string_view method, const StepControl& control, double t_end,
                         double output_dt);

// |y_stop - exact(t_end)|inf for a run that reached t_end on a model with an exact solution; empty otherwise
std::optional<double> exact_error(const Model& model, const RunResult& result, double t_end);

// m.error from exact_error; a run whose error is not finite (its state or the exact solution overflowing) is
// diverged at t_end, saying so, never `ok` (the one place: run, render, the studies and split runs measure here)
void measure_error(const Model& model, Measured& m, double t_end);

// a run timed for a comparison of costs: one shorter than short_run_seconds (thread CPU) is run again, up to
// `runs` times in all, and the least kept. Timer resolution, first-touch costs and an interruption are
// microseconds to a millisecond: a large share of a run of a few milliseconds, little of a longer one. A run
// that fails is not run again
constexpr double short_run_seconds = 0.05;
Measured least_of_runs(const Model& model, std::string_view method, const StepControl& control, double t_end, int runs);

// |a - b|inf
double max_norm_error(const Eigen::VectorXd& a, const Eigen::VectorXd& b);

}  // namespace stepwise
