// The wind on a triangle of cloth (seeds: the flag): the force k_w ((w - vbar) . N) N / |N| on a triangle with
// area vector N = (x_b - x_a) x (x_c - x_a) / 2 whose corners move at mean velocity vbar, a third of it on
// each corner. The cloth model (models/cloth.cpp), its node-by-node step (solvers/cloth_grid.hpp) and the
// gpu-cloth shader share it.
#pragma once

#include <stepwise/kernels/vec3.hpp>

namespace stepwise {

template <class V>
V area_vector(const V& xa, const V& xb, const V& xc) {
  return cross(xb - xa, xc - xa) / Scalar<V>(2);
}

template <class V>
V mean_velocity(const V& va, const V& vb, const V& vc) {
  return ((va + vb) + vc) / Scalar<V>(3);
}

// a third of the wind's force on a triangle of area vector n, corners moving at mean velocity `mean`, in the
// wind w with coefficient k (kg/s per m^2 of area: N s/m^3)
template <class V, class T>
V wind_share(const V& n, const V& mean, const V& wind, T k) {
  return ((k * dot(wind - mean, n)) * n) / (T(3) * norm(n));
}

}  // namespace stepwise
