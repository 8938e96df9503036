// The pendulum of pendulum.hpp as a point mass in the plane held by one distance constraint |x| = L (the
// constrained scene). State y = (x, y, vx, vy) [m, m/s], the pivot at the origin, y up; parameters those of the
// pendulum (theta0, omega0, g, length, mass) and the constraint's compliance alpha [m/N] (0: a rigid rod).
//
// Its f, for the ODE methods, is the constrained equation of motion with the rod's force as a Lagrange
// multiplier (index reduced to 1: the constraint's second derivative held at zero), which keeps |x| = L only as
// well as the method's error lets it (it drifts):
//   alpha = 0:  a = g + lambda x,  lambda = -(|v|^2 + x . g) / |x|^2
//   alpha > 0:  a = g - (|x| - L) / (m alpha) x / |x|      (a spring of stiffness 1/alpha)
// Position-based methods step it through the DistanceConstraints capability instead (gravity, then the
// constraint projected). A compliant rod is also a mass-spring system in the plane (MassSpringView, one pinned
// spring: models/springs.hpp's SpringNetwork), for the methods of backward Euler's incremental potential (vbd,
// implicit-euler, implicit-euler-newton) and the prefactored fast-mass-spring. Exact (alpha = 0): the reduced pendulum's theta(t) at x = L (sin theta, -cos theta),
// v = L omega (cos theta, sin theta). Energy m |v|^2 / 2 + m g y (+ (|x| - L)^2 / (2 alpha)).
#pragma once

#include <stepwise/models/model.hpp>

namespace stepwise {

std::span<const ParamSpec> pendulum_cartesian_params();

std::unique_ptr<Model> make_pendulum_cartesian(const Params& params);

}  // namespace stepwise
