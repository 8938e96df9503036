// The state at t_end a scene without an exact solution is measured against: a converged run, checked by a second,
// unrelated method at the same tight tolerance. Non-stiff systems: GSL's Prince-Dormand 8(9) and the project's
// Verner 9(8) (two codes, two tableaus). Where either explicit run cannot finish in its step budget (a stiff
// system: its fast modes hold an explicit method to tiny steps), the stiff pair: CVODE's BDF and GSL's
// Bader-Deuflhard extrapolation (a multistep and a one-step code). Their difference is the reference's own
// uncertainty, said wherever an error is measured against it.
#pragma once

#include <stepwise/models/model.hpp>

#include <string>

namespace stepwise {

struct Reference {
  Eigen::VectorXd y;       // the first method's state at t_end
  std::string methods;     // "gsl-rk8pd and verner98 at rtol 1e-13"
  double agreement = 0;    // |y1 - y2|inf: how far the two runs are apart
  bool stiff_pair = false; // the explicit pair could not finish
};

// the reference of `model` at t_end; std::runtime_error naming the methods where no pair finishes
Reference converged_reference(const Model& model, double t_end);

}  // namespace stepwise
