#include "contact_checks.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace stepwise {

Params box_on_slope(double slope, double friction) {
  const double hz = resolve_params(*find_model("dropped-body"), {}).at("hz");  // the default box's, resting on its largest face
  return {{"ground_slope", slope}, {"qw0", std::cos(slope / 2)}, {"qx0", 0}, {"qy0", std::sin(slope / 2)}, {"qz0", 0},
          {"x0", hz * std::sin(slope)}, {"y0", 0}, {"z0", hz * std::cos(slope)}, {"vx0", 0}, {"vy0", 0}, {"vz0", 0},
          {"wx0", 0}, {"wy0", 0}, {"wz0", 0}, {"friction", friction}};
}

SlopeMotion slope_motion(const RunResult& run, double slope, double settled_at) {
  const Eigen::Vector3d n(std::sin(slope), 0, std::cos(slope)), along(std::cos(slope), 0, -std::sin(slope));
  const auto& ts = run.trajectory.t;
  const auto& ys = run.trajectory.y;
  SlopeMotion m;
  if (ys.empty()) return m;
  const size_t settled = static_cast<size_t>(std::lower_bound(ts.begin(), ts.end(), settled_at) - ts.begin());
  const Eigen::VectorXd& start = ys.front();
  const Eigen::VectorXd& rest = ys[std::min(settled, ys.size() - 1)];
  const Eigen::Quaterniond q_rest(rest[6], rest[7], rest[8], rest[9]);
  for (size_t k = 0; k < ys.size(); ++k) {
    const Eigen::VectorXd& y = ys[k];
    m.sink = std::max(m.sink, -(y.segment<3>(0) - start.segment<3>(0)).dot(n));
    if (k < settled) continue;
    const Eigen::Vector3d d = y.segment<3>(0) - rest.segment<3>(0);
    m.creep = std::max({m.creep, std::abs(d.dot(along)), std::abs(d.y())});
    m.turn = std::max(m.turn, Eigen::Quaterniond(y[6], y[7], y[8], y[9]).angularDistance(q_rest));
  }
  m.speed = ys.back().segment<3>(3).dot(along);
  return m;
}

}  // namespace stepwise
