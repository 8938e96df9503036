// The response of rigid bodies in contact (seeds: collision, the general case, for bodies that turn), the
// numerics of sequential-impulses (solvers/methods/sequential_impulses.cpp); the contacts themselves come
// from the model's geometry (ContactBodiesView::find_contacts).
//
// Response. At each contact the relative velocity of the two body points u = (v_a + w_a x r_a) -
// (v_b + w_b x r_b) answers an impulse j (+j on a, -j on b) linearly, u += K j, with the collision matrix
//   K = (1/m_a + 1/m_b) 1 - [r_a]x I_a^-1 [r_a]x - [r_b]x I_b^-1 [r_b]x   (world inertia I = R I_body R^T)
// (Mirtich & Canny, "Impulse-based simulation of rigid bodies", 1995; Guendelman, Bridson & Fedkiw,
// "Nonconvex rigid bodies with stacking", SIGGRAPH 2003). All contacts are solved together by projected
// Gauss-Seidel on accumulated impulses (Catto, "Iterative dynamics with temporal coherence", GDC 2005):
// per contact the normal impulse lambda_n >= 0 drives the normal velocity to its target, -eps u_n at an
// impact (approach faster than the resting speed), 0 otherwise; the tangential impulse drives the sliding
// velocity to zero, held inside Coulomb's cone |lambda_t| <= mu lambda_n. Sweeps repeat until no impulse
// changes the velocity at its contact by more than a tolerance. A resting contact starts from the impulse
// it had at the last step (warm start, Catto 2005): a stack's impulses change little from step to step,
// and Gauss-Seidel from zero needs sweeps growing with the square of the stack's height.
// The kinetic energy change of impulses is exact: dT = sum_i j_i . u_i(before) + the quadratic form of the
// j_i, computed directly from the velocities. Gauss-Seidel with restitution and friction together can
// raise it (Kane's paradox for one contact; simultaneous restitution for several): when dT > 0 the
// velocities are restored and frictionless impulses are applied one contact at a time instead, each
// j = -(1 + eps) u_n / (n.K n) n only where the contact approaches, which cannot: it changes T by
// -(1 - eps^2) u_n^2 / (2 n.K n) <= 0 for eps <= 1. The outcome says when this happened.
// Penetration left by a step is pushed out along the deepest contact of each pair that is not separating
// (resting contact), a fraction of its depth beyond a tolerance, split by inverse mass: positions only, so
// no kinetic energy is added and the centre of mass stays; the angular momentum about a point changes by
// m_a d_a x (v_a - v_b), which is why pairs that separate (after an impact) are left to do it by themselves.
#pragma once

#include <stepwise/solvers/capabilities/contact_bodies.hpp>

#include <span>

namespace stepwise {

// the impulses of the contacts on y's velocities, then the push out of penetration; the sweeps start from
// the impulses memory has for the same contacts (not at impacts), and memory receives this resolution's
ContactOutcome resolve(std::span<const BodyMass> bodies, std::span<const Contact> contacts, const ContactMaterial& material,
                       Eigen::Ref<Eigen::VectorXd> y, ContactMemory& memory);

// one step's resolution for a system offering bodies in contact: its contacts at y found by the model, an
// approach slower than two steps of gravity taken as resting, the last step's impulses as the warm start
// (unless the system turns it off), dt the step the velocities were advanced by
ContactOutcome resolve_contacts(const ContactBodiesView& view, Eigen::Ref<Eigen::VectorXd> y, double dt, ContactMemory& memory);

// Gauss-Seidel's sweeps stop when no impulse changed the velocity at its contact by more than this (m/s):
// a resting body creeps by at most this times the time it rests
inline constexpr double contact_velocity_tolerance = 1e-10;
// and after this many at most: Gauss-Seidel converges linearly, as slowly as 0.993 a sweep in a collapsing
// stack (measured), where 200 sweeps leave about 1e-6 m/s; a resting column of 5 warm-started needs 1 to 4
inline constexpr int contact_max_sweeps = 200;
// a kinetic energy rise from the impulses below this fraction is round-off of the sums, not a rise (the
// guard acts above it)
inline constexpr double contact_energy_roundoff = 1e-12;

}  // namespace stepwise
