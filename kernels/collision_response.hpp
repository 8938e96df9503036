// A point meeting a surface of unit normal n with velocity v (v . n < 0): the normal velocity reversed and
// scaled by the restitution eps, the tangential one reduced by Coulomb friction, mu times the normal impulse
// (1 + eps) |v . n|, and stopped at zero (seeds: collision response). The particles' planes and meshes
// (models/plane_collision.cpp), the cloth's sphere and ground (the model's projection, its node-by-node step
// in solvers/cloth_grid.hpp at eps = 0, and the gpu-cloth shader) share it.
#pragma once

#include <stepwise/kernels/vec3.hpp>

#include <algorithm>
#include <cmath>

namespace stepwise {

template <class V, class T>
V collision_response(const V& v, const V& n, T restitution, T friction) {
  const T vn = dot(v, n);
  const V tangential = v - vn * n;
  const T impulse = (1 + restitution) * std::abs(vn);
  const T speed = norm(tangential);
  const T kept = speed > 0 ? std::max(T(0), speed - friction * impulse) / speed : T(0);
  return (-restitution * vn) * n + kept * tangential;
}

}  // namespace stepwise
