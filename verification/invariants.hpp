// How far a run strays from the invariants of a torque-free rigid body: its energy and its world angular
// momentum (the summary's last three entries), over the first and the second half of its trajectory, so a
// drift (growing) tells itself from a bounded error (the same in both halves). Shared by the tests and the
// report's rigid-body study.
#pragma once

#include <stepwise/models/model.hpp>
#include <stepwise/solvers/integrator.hpp>

namespace stepwise {

struct InvariantDrift {
  double energy[2] = {0, 0};    // largest |E/E0 - 1| over the first and the second half
  double momentum[2] = {0, 0};  // largest |L - L0| / |L0|
};

InvariantDrift rigid_body_drift(const Model& model, const RunResult& run);

// one state's |E/E0 - 1| and |L - L0| / |L0| against the model's initial state
struct InvariantError {
  double energy = 0, momentum = 0;
};
InvariantError rigid_body_error(const Model& model, const Eigen::VectorXd& y);

}  // namespace stepwise
