// The state at t_end a scene without an exact solution is measured against: a converged run, checked by a second,
// unrelated method at the same tight tolerance. Non-stiff systems: GSL's Prince-Dormand 8(9) and the project's
// Verner 9(8) (two codes, two tableaus). Where either explicit run cannot finish in its step budget (a stiff
// system: its fast modes hold an explicit method to tiny steps), the stiff pair: CVODE's BDF and GSL's
// Bader-Deuflhard extrapolation (a multistep and a one-step code), or on a system too large for the latter's dense
// matrices (a PDE's grid) the project's RODAS5 on its sparse LU. Their difference is the reference's own
// uncertainty, said wherever an error is measured against it.
#pragma once

#include <stepwise/models/model.hpp>
#include <stepwise/run/measure.hpp>
#include <stepwise/solvers/integrator.hpp>

#include <chrono>
#include <functional>
#include <stdexcept>
#include <string>

namespace stepwise {

struct Reference {
  Eigen::VectorXd y;       // the first method's state at t_end
  std::string methods;     // "gsl-rk8pd and verner98 at rtol 1e-13"
  double agreement = 0;    // |y1 - y2|inf: how far the two runs are apart
  bool stiff_pair = false; // the explicit pair could not finish
};

// a deadline for the reference (a budgeted command's share), and where its progress is said while it runs
struct ReferenceLimit {
  std::chrono::steady_clock::time_point deadline;
  std::function<void(const std::string& line)> progress;  // about once a second: which run, how far
};

// the deadline passed before the reference was had: which run was cut, how far it got, what it had cost
struct ReferenceOutOfTime : std::runtime_error {
  ReferenceOutOfTime(const std::string& what, double estimated_seconds) : std::runtime_error(what), estimated_seconds(estimated_seconds) {}
  double estimated_seconds;  // what the whole reference would take, extrapolated from how far the cut run got
};

// one reference run of `method` from t = 0 to t_end, under `limit` where given (its progress said as `what`):
// ReferenceOutOfTime where the deadline cuts it, estimating the whole from `spent_before` (s) and this run's pace for
// it and the `runs_after` of the same cost still to make
Measured reference_run(const Model& model, const std::string& method, const StepControl& control, double t_end, const ReferenceLimit* limit,
                       double spent_before, int runs_after, const std::string& what);

// the reference of `model` at t_end; std::runtime_error naming the methods where no pair finishes, and
// ReferenceOutOfTime where `limit`'s deadline passes first
Reference converged_reference(const Model& model, double t_end, const ReferenceLimit* limit = nullptr);

}  // namespace stepwise
