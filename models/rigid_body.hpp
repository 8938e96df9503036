// One rigid body (seeds: three translational and three rotational degrees of freedom; m a = f,
// d(I w)/dt = T), in the principal frame of its inertia tensor (models/mass_properties.hpp gives it
// for a mesh).
//
// State, 13 entries: centre of mass x (m), velocity v (m/s), orientation q = (qw, qx, qy, qz), a unit
// quaternion taking body to world coordinates, and the angular velocity w in the body frame (rad/s):
//   dx/dt = v
//   m dv/dt = m g_vec - m k v + f                  (g_vec = (0, 0, -g); k = drag, 1/s; f a constant world force)
//   dq/dt = q (x) (0, w) / 2
//   I dw/dt = (I w) x w - c I w + r x (R^T f)      (Euler's equations, I = diag(I1, I2, I3); c = angular_drag,
//                                                    1/s; f applied at the body point r)
// R is the rotation of q / |q|: the right-hand side is defined off the unit sphere, and every integrator
// takes q back to it after each step (its Projection capability; counted as `projections`).
// Energy: m |v|^2 / 2 + w^T I w / 2 + m g z. The world angular momentum L = R I w is conserved without
// torque; summary.json's final_state carries it as Lx, Ly, Lz beside the state.
//
// Torque-free, Euler's equations have a closed solution in Jacobi's elliptic functions (Landau &
// Lifshitz, Mechanics, section 37): with the moments sorted I_a < I_b < I_c as the motion needs
// (M^2 = |I w|^2 against 2 E_rot I_b), w_a = A_a cn(tau, k), w_b = A_b sn(tau, k), w_c = A_c dn(tau, k),
//   A_a^2 = (2E I_c - M^2) / (I_a (I_c - I_a)),  A_b^2 = (2E I_c - M^2) / (I_b (I_c - I_b)),
//   A_c^2 = (M^2 - 2E I_a) / (I_c (I_c - I_a)),  tau = s (t - t0),  s^2 = (I_c - I_b)(M^2 - 2E I_a) / (I_a I_b I_c),
//   k^2 = (I_b - I_a)(2E I_c - M^2) / ((I_c - I_b)(M^2 - 2E I_a)),
// where (a, b, c) = (1, 2, 3) of the sorted moments if M^2 > 2E I_2 and (3, 2, 1) otherwise. The
// components are periodic with period 4 K(k) / s: near the intermediate axis w_b changes sign twice a
// period (the tennis-racket flip).
#pragma once

#include <stepwise/kernels/rigid_body.hpp>

#include <stepwise/models/model.hpp>
#include <stepwise/models/triangle_mesh.hpp>

#include <Eigen/Geometry>

namespace stepwise {

std::span<const ParamSpec> rigid_body_params();

// One body's 13-entry state (x, v, q, w; w in the principal frame), shared by the rigid-body models:
// the scene's initial orientation (qw0, qx0, qy0, qz0) normalised, BadParameter("qw0") when all are zero
Eigen::Quaterniond initial_orientation(const Params& params);
// x, y, z, vx, ... wz for one body; x[i], ... wz[i] for several
std::vector<std::string> rigid_body_state_names(int bodies);
// (its kinetic energy: kernels/rigid_body.hpp's body_kinetic_energy)
// the world angular momentum about the centre of mass, R I w, of the body state y
Eigen::Vector3d body_angular_momentum(const Eigen::Vector3d& inertia, const Eigen::Ref<const Eigen::VectorXd>& y);
// dq/dt = q (x) (0, w) / 2 and the torque-free Euler equations I dw/dt = (I w) x w, into dydt's entries 6..12
void free_rotation_rates(const Eigen::Vector3d& inertia, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt);
std::unique_ptr<Model> make_rigid_body(const Params& params);
// the body bounded by a closed mesh of uniform `density`: mass and principal moments from it (polyhedral
// mass properties), the orientation given taken as the mesh's and turned onto its principal axes (w0 and
// the force's point stay in the principal frame). Mass and I1-I3 may not be set as well (BadParameter
// naming them); BadParameter with key "mesh" for a mesh that is open, inside out or empty
std::unique_ptr<Model> make_rigid_body(const Params& params, const TriangleMesh& mesh);

// Euler's torque-free equations solved in closed form for principal moments `inertia` (any order) from
// body angular velocity w0 at t = 0
class TorqueFreeRotation {
 public:
  TorqueFreeRotation(const Eigen::Vector3d& inertia, const Eigen::Vector3d& w0);
  Eigen::Vector3d omega(double t) const;
  // the period of the angular velocity (s); infinite on the separatrix (k = 1) and for a body spinning
  // about a principal axis (nothing to period)
  double period() const { return period_; }

 private:
  Eigen::Vector3d w0_;
  bool steady_ = false;        // spinning about a principal axis, or a body with equal moments
  int a_ = 0, b_ = 1, c_ = 2;  // axes taking the roles of cn, sn, dn
  double amp_[3] = {0, 0, 0};  // signed amplitudes of w_a, w_b, w_c
  double s_ = 0, m_ = 0, tau0_ = 0, period_ = 0, quarter_ = 0;  // rate, parameter k^2, phase, period, K(k)
};

}  // namespace stepwise
