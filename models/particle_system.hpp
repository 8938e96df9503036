// A particle system in a force field (seeds: particle systems; particles in a force field).
//
// N particles of unit mass, each pulled by a harmonic trap towards the origin, falling under gravity and
// slowed by linear drag:
//
//   a_i = -k x_i - gamma v_i - g e_z + sum_j f_ij
//
// with an optional short-range repulsion between particles closer than the radius r_c, the force of the
// soft-sphere potential U(r) = s (r_c - r)^2 / 2 (as in discrete-element and DPD models):
//
//   f_ij = s (r_c - r) (x_i - x_j) / r   for r = |x_i - x_j| < r_c (none for coincident particles),
//
// found through a uniform grid of cells no smaller than r_c (cell_list.hpp), never by testing all pairs.
// s = 0 switches it off.
//
// Energy per unit mass E = sum |v_i|^2 / 2 + k |x_i|^2 / 2 + g z_i + sum_pairs U(r_ij), conserved when
// gamma = 0 and dissipated by drag at the rate gamma sum |v_i|^2.
//
// Exact solution without repulsion: every coordinate obeys u'' + gamma u' + k u = 0 about the equilibrium
// x* = (0, 0, -g/k), whose flow is e^{At} = e^{-gamma t/2} [C(t) I + S(t) (A + gamma/2 I)] with
// A = [[0, 1], [-k, -gamma]] and, for Delta = gamma^2/4 - k, C = cos(wt), S = sin(wt)/w (w^2 = -Delta > 0),
// C = cosh(qt), S = sinh(qt)/q (q^2 = Delta > 0), or C = 1, S = t (critical damping).
//
// state: positions x[i], y[i], z[i] (m), then velocities vx[i], vy[i], vz[i] (m/s); the state is too large
// to write particle by particle, so trajectory.csv and final_state carry a summary (summary_names()).
// Initial positions uniform in [-spread, spread]^3 and velocities in [-speed, speed]^3 from the seeded
// stream of particle_common.hpp.
#pragma once

#include <stepwise/models/model.hpp>

namespace stepwise {

std::span<const ParamSpec> particle_system_params();
std::unique_ptr<Model> make_particle_system(const Params& params);

}  // namespace stepwise
