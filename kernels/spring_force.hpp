// The seeds' spring: Hooke's law with Voigt damping along the spring,
//   F = (c (|r| - l) + gamma u . dr/dt) u,   u = r / |r|,
// the force on the end a of a spring whose other end b is r = x_b - x_a away, closing at dr/dt = v_b - v_a
// (-F on b). The mass-spring models (models/springs.cpp, scattering it over a spring list), the cloth's
// node-by-node step (solvers/cloth_grid.hpp, gathering it at each node, in float32 and float64) and the
// gpu-cloth shader (whose GLSL is held to this by test_gpu_shader's bitwise comparison) share it.
#pragma once

#include <stepwise/kernels/vec3.hpp>

namespace stepwise {

// V: Eigen::Vector3d or Vec3<T>; stiffness c (N/m), damping gamma (N s/m), rest length l (m)
template <class V, class T>
V spring_force(const V& r, const V& closing, T rest, T stiffness, T damping) {
  const T length = norm(r);
  const V u = r / length;
  return (stiffness * (length - rest) + damping * dot(u, closing)) * u;
}

}  // namespace stepwise
