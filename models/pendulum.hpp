// The simple pendulum (seeds: "the pendulum", slide on the equation of motion and its small-angle model).
//
//   nonlinear:    theta'' + (g/L) sin theta = 0
//   small-angle:  theta'' + (g/L) theta = 0           (sin theta ~ theta)
//
// state y = (theta [rad], omega = dtheta/dt [rad/s]); parameters theta0 [rad], omega0 [rad/s],
// g [m/s^2], length L [m], mass m [kg]. With w = sqrt(g/L):
//
// Exact nonlinear solution (libration, k < 1), e.g. Lawden, "Elliptic Functions and Applications", §5.2:
//   k^2 = sin^2(theta0/2) + omega0^2 / (4 w^2)          (energy: the turning angle is 2 asin k)
//   theta(t) = 2 asin(k sn(w t + u0 | k^2)),  omega(t) = 2 k w cn(w t + u0 | k^2)
//   u0 = F(phi0, k), phi0 = atan2(sin(theta0/2)/k, omega0/(2 k w)),   period T = 4 K(k) / w
// For k >= 1 (the pendulum goes over the top) no exact solution is offered.
// Small-angle exact: theta(t) = theta0 cos(w t) + (omega0/w) sin(w t).
//
// Energy: nonlinear E = m L^2 omega^2 / 2 + m g L (1 - cos theta); small-angle E = m L^2 omega^2 / 2 + m g L theta^2 / 2.
#pragma once

#include <stepwise/models/model.hpp>

namespace stepwise {

std::span<const ParamSpec> pendulum_params();

std::unique_ptr<Model> make_pendulum(const Params& params, bool small_angle);

// period of the nonlinear pendulum released from rest at amplitude theta0 < pi: 4 K(sin(theta0/2)) / w
double pendulum_period(double theta0, double g, double length);

}  // namespace stepwise
