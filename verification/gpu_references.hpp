// The cloth's CPU references for gpu-cloth: solvers/cloth_grid.hpp's step, node by node, in
// float32 (the operations the GPU's pass performs, in its order: what a conforming GPU must match) or in
// float64 (what the model's own symplectic Euler computes, to its round-off), and the scale of the
// round-off bound both are held to (tolerances.hpp's cloth_step_bound). The water's references are in
// wave_modes.hpp.
#pragma once

#include <stepwise/solvers/cloth_grid.hpp>
#include <stepwise/verification/tolerances.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace stepwise {

// the bound's scale over a grid state: the largest |x|, |v| components, and the acceleration scale A from
// the longest spring (cloth_step_bound's terms), folded into `scale`
template <class T>
void widen_roundoff_scale(const ClothGridView& view, const cloth_grid::State<T>& s, tolerance::ClothRoundoffScale& scale) {
  double spring_length = 0;
  for (int r = 0; r < view.rows; ++r)
    for (int c = 0; c < view.columns; ++c) {
      const auto& x = s.x[static_cast<size_t>(r * view.columns + c)];
      const auto& v = s.v[static_cast<size_t>(r * view.columns + c)];
      scale.max_x = std::max({scale.max_x, std::abs(double(x.x)), std::abs(double(x.y)), std::abs(double(x.z))});
      scale.max_v = std::max({scale.max_v, std::abs(double(v.x)), std::abs(double(v.y)), std::abs(double(v.z))});
      for (const auto& n : cloth_grid::neighbours) {
        const int rq = r + n.dr, cq = c + n.dc;
        if (rq < 0 || rq >= view.rows || cq < 0 || cq >= view.columns) continue;
        spring_length = std::max(spring_length, double(norm(s.x[static_cast<size_t>(rq * view.columns + cq)] - x)));
      }
    }
  const double rest = 2 * std::max(view.across, view.down);
  const double stiffness = *std::max_element(view.stiffness.begin(), view.stiffness.end());
  const double forces = 12 * stiffness * (spring_length + rest) + 12 * view.damping * 2 * scale.max_v +
                        6 * view.wind_coefficient * (view.wind.norm() * (1 + std::abs(view.gust_amplitude)) + scale.max_v) * spring_length * spring_length / 2 +
                        view.pick_force.norm();
  scale.acceleration = std::max(scale.acceleration, forces / view.node_mass + view.drag * scale.max_v + view.g);
}

// `steps` steps of h from y0 at t0 (step k at t0 + k h), the scale of every state passed folded into `scale`
template <class T>
cloth_grid::State<T> run_cloth_grid(const ClothGridView& view, const Eigen::VectorXd& y0, double t0, double h, long steps,
                                    tolerance::ClothRoundoffScale& scale) {
  cloth_grid::State<T> s = cloth_grid::spread<T>(view, y0), next;
  widen_roundoff_scale(view, s, scale);
  for (long k = 0; k < steps; ++k) {
    cloth_grid::step(cloth_grid::constants<T>(view, t0 + static_cast<double>(k) * h, h), view.free_index, s, next);
    std::swap(s, next);
    widen_roundoff_scale(view, s, scale);
  }
  return s;
}

// the 2-norm of the difference of two grid states' positions
template <class A, class B>
double position_difference(const cloth_grid::State<A>& a, const cloth_grid::State<B>& b) {
  double sum = 0;
  for (size_t k = 0; k < a.x.size(); ++k) {
    const double dx = double(a.x[k].x) - double(b.x[k].x), dy = double(a.x[k].y) - double(b.x[k].y), dz = double(a.x[k].z) - double(b.x[k].z);
    sum += dx * dx + dy * dy + dz * dz;
  }
  return std::sqrt(sum);
}

}  // namespace stepwise
