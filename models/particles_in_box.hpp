// Particles bouncing in a box (seeds: particle systems, collision with a plane).
//
// N particles of unit mass in the cube [0, L]^3 under gravity -g z; the six walls are planes with inward
// normals, and every particle-wall pair is an event g = d(p_i) = (p_i - p0) . n falling through zero, whose
// response is plane_collision's: n . v2 = -eps n . v1, tangential kept less Coulomb friction mu. A rebound
// off the floor slower than rest_speed ends in resting contact (the normal velocity set to zero exactly,
// after which the floor's normal force cancels gravity), so no particle chatters towards a Zeno point.
// Particles do not interact.
//
// state: positions x[i], y[i], z[i] (m) for i < N, then velocities vx[i], vy[i], vz[i] (m/s).
// Initial positions uniform in the box (a margin of L/20 from each wall), velocities uniform in
// [-speed, speed]^3, from a 64-bit Mersenne twister seeded with `seed`: the same seed gives the same run.
// Energy E = sum |v_i|^2 / 2 + g z_i per unit mass; each impact removes (1 - eps^2) (n . v)^2 / 2 and friction more.
#pragma once

#include <stepwise/models/model.hpp>

namespace stepwise {

std::span<const ParamSpec> particles_in_box_params();
std::unique_ptr<Model> make_particles_in_box(const Params& params);

}  // namespace stepwise
