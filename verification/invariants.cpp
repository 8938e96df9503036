#include "invariants.hpp"

#include <algorithm>
#include <cmath>

namespace stepwise {

InvariantError rigid_body_error(const Model& model, const Eigen::VectorXd& y) {
  const Eigen::VectorXd y0 = model.initial_state();
  const Eigen::Vector3d l0 = model.summary(y0).tail<3>();
  return {std::abs(*model.energy(y) / *model.energy(y0) - 1), (Eigen::Vector3d(model.summary(y).tail<3>()) - l0).norm() / l0.norm()};
}

InvariantDrift rigid_body_drift(const Model& model, const RunResult& run) {
  InvariantDrift d;
  const size_t n = run.trajectory.t.size();
  for (size_t i = 0; i < n; ++i) {
    const int half = 2 * i < n ? 0 : 1;
    const InvariantError e = rigid_body_error(model, run.trajectory.y[i]);
    d.energy[half] = std::max(d.energy[half], e.energy);
    d.momentum[half] = std::max(d.momentum[half], e.momentum);
  }
  return d;
}

}  // namespace stepwise
