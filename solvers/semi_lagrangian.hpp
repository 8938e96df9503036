// Semi-Lagrangian transport on a periodic n x n grid (fluid_grid.hpp's layout), in grid units: point (i, j)
// at x = j, y = i, a value q[i n + j], one period n in each direction. `stable-fluids` advects with these two:
//
//   sample:  q at any (x, y), bilinear in the four surrounding points (wrapped): exact for q linear between
//            them, second order in the spacing otherwise;
//   trace:   where the point that reaches (j, i) in time h along the velocity (u, v) comes from, by the
//            midpoint rule on the characteristic dx/dt = u(x):
//              x_mid = x - (s/2) u(x),   x_back = x - s u(x_mid),   s = h / d   (d the spacing, u in m/s),
//            the velocity at x_mid sampled bilinearly. One trace is second-order accurate in h: its error
//            against the exact characteristic is O(h^3) where the velocity is smooth (the midpoint rule's
//            local error), and nothing more where sampling u is exact (a linear flow).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace stepwise::semi_lagrangian {

// q (n x n) at (x, y) in grid units, bilinear, periodic; with `lo` and `hi`, the least and greatest of the four
// points it lies between
inline double sample(const double* q, int n, double x, double y, double* lo = nullptr, double* hi = nullptr) {
  const double fx = std::floor(x), fy = std::floor(y);
  const double ax = x - fx, ay = y - fy;
  const auto wrap = [n](double c) {  // the division only for points more than a period away
    long w = static_cast<long>(c);
    if (w >= 0 && w < n) return static_cast<Eigen::Index>(w);
    if (w >= -n && w < 0) return static_cast<Eigen::Index>(w + n);
    w %= n;
    return static_cast<Eigen::Index>(w < 0 ? w + n : w);
  };
  const Eigen::Index j0 = wrap(fx), j1 = j0 + 1 == n ? 0 : j0 + 1, i0 = wrap(fy), i1 = i0 + 1 == n ? 0 : i0 + 1;
  const double q00 = q[i0 * n + j0], q01 = q[i0 * n + j1], q10 = q[i1 * n + j0], q11 = q[i1 * n + j1];
  if (lo) {
    *lo = std::min({q00, q01, q10, q11});
    *hi = std::max({q00, q01, q10, q11});
  }
  return (1 - ay) * ((1 - ax) * q00 + ax * q01) + ay * ((1 - ax) * q10 + ax * q11);
}

// bx, by (n x n each): for every grid point, where its value comes from over a step of s = h / d grid units of
// time (unwrapped grid units; negative s traces forward), along (u, v) (n x n each, m/s)
inline void trace(const double* u, const double* v, int n, double s, double* bx, double* by) {
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Eigen::Index k = static_cast<Eigen::Index>(i) * n + j;
      const double mx = j - 0.5 * s * u[k], my = i - 0.5 * s * v[k];
      bx[k] = j - s * sample(u, n, mx, my);
      by[k] = i - s * sample(v, n, mx, my);
    }
}

}  // namespace stepwise::semi_lagrangian
