// A particle in a force field: gravity and optional linear drag (seeds: "particle in a force field",
// explicit against implicit Euler).
//
//   x'' = -k x',   y'' = -g - k y'        (k = drag [1/s], the drag force per unit mass and velocity)
//
// state y = (x, y [m], vx, vy [m/s]); parameters x0, y0, vx0, vy0, g [m/s^2], drag k [1/s], mass [kg].
// Exact, with E(t) = (1 - e^{-k t}) / k  (-> t as k -> 0):
//   vx = vx0 e^{-k t},             x = x0 + vx0 E(t)
//   vy = (vy0 + g/k) e^{-k t} - g/k, y = y0 + (vy0 + g/k) E(t) - g t / k
// written without the g/k cancellation as vy = vy0 e^{-kt} - g E(t), y = y0 + vy0 E(t) - g (t - E(t)) / k.
// Energy E = m |v|^2 / 2 + m g y (conserved without drag, decreasing with it).
#pragma once

#include <stepwise/models/model.hpp>

namespace stepwise {

std::span<const ParamSpec> projectile_params();
std::unique_ptr<Model> make_projectile(const Params& params);

}  // namespace stepwise
