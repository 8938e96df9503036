#include "invariants.hpp"

#include <algorithm>
#include <cmath>

namespace stepwise {

InvariantDrift rigid_body_drift(const Model& model, const RunResult& run) {
  const Eigen::VectorXd y0 = model.initial_state();
  const double e0 = *model.energy(y0);
  const Eigen::Vector3d l0 = model.summary(y0).tail<3>();
  InvariantDrift d;
  const size_t n = run.trajectory.t.size();
  for (size_t i = 0; i < n; ++i) {
    const int half = 2 * i < n ? 0 : 1;
    const Eigen::VectorXd& y = run.trajectory.y[i];
    d.energy[half] = std::max(d.energy[half], std::abs(*model.energy(y) / e0 - 1));
    d.momentum[half] = std::max(d.momentum[half], (Eigen::Vector3d(model.summary(y).tail<3>()) - l0).norm() / l0.norm());
  }
  return d;
}

}  // namespace stepwise
