// Capability: one torque-free rigid body, y = (x, v, q, w), 13 entries: position (3, m), velocity (3, m/s),
// orientation as a unit quaternion (w, x, y, z; body to world) and the angular velocity in the body's
// principal frame (3, rad/s), under a constant linear acceleration: the structure the splitting of the
// free rigid body into exact rotations needs (rigid-splitting).
#pragma once

#include <stepwise/solvers/ode_system.hpp>

namespace stepwise {

struct RigidBodyView {
  Eigen::Vector3d inertia;       // principal moments I1, I2, I3 (kg m^2)
  Eigen::Vector3d acceleration;  // constant linear acceleration (m/s^2)
};

inline const Requirement needs_free_rigid_body =
    needs<RigidBodyView>("a torque-free rigid body (a rigid-body scene without drag or torque)");

}  // namespace stepwise
