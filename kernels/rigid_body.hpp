// Formulas of a rigid body in the 13-entry state (x, v, q, w: position, velocity, unit quaternion body to
// world, angular velocity in the body's principal frame), shared by the models that describe bodies and the
// contact solve that changes their velocities.
#pragma once

#include <Eigen/Dense>
#include <Eigen/Geometry>

namespace stepwise {

// where body `body` of a state of 13-entry bodies is, and how it is turned
struct Pose {
  Eigen::Vector3d x;  // centre of mass, world (m)
  Eigen::Matrix3d R;  // body to world
};

inline Pose pose(const Eigen::VectorXd& y, int body) {
  const int o = 13 * body;
  return {y.segment<3>(o), Eigen::Quaterniond(y[o + 6], y[o + 7], y[o + 8], y[o + 9]).normalized().toRotationMatrix()};
}

// m |v|^2 / 2 + w . I w / 2 (J), w in the principal frame and I its principal moments
inline double body_kinetic_energy(double mass, const Eigen::Vector3d& inertia, const Eigen::Vector3d& v, const Eigen::Vector3d& w) {
  return mass * v.squaredNorm() / 2 + w.dot(inertia.cwiseProduct(w)) / 2;
}

}  // namespace stepwise
