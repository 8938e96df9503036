// The cloth's forces node by node, as ClothGridView (solvers/capabilities/cloth_grid.hpp) describes them, in a precision
// of the caller's choosing: what a pass that gives each node to one thread computes (gpu-cloth's fragment
// shader, solvers/gpu/gpu_cloth.cpp, whose GLSL performs these operations in this order) and its float32
// CPU reference (verification/gpu_references.hpp). They are models/cloth.cpp's forces, gathered where the
// model scatters: a node sums its own twelve springs and the wind on its six triangles. Each spring's force
// and each triangle's share is computed by every node it acts on with the same operations on the same
// values, so it is the scatter's to the bit; only the order of a node's sum differs (in float64, round-off:
// test_gpu_shader holds the two to it).
//
// The formulas are kernels/'s (spring_force, wind_share, collision_response), on Vec3<T>, whose every
// operation is written out so that its order is fixed.
#pragma once

#include <stepwise/kernels/collision_response.hpp>
#include <stepwise/kernels/spring_force.hpp>
#include <stepwise/kernels/vec3.hpp>
#include <stepwise/kernels/wind.hpp>
#include <stepwise/solvers/capabilities/cloth_grid.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <span>
#include <vector>

namespace stepwise::cloth_grid {

// the twelve springs of a node in the order it sums them: (row offset, column offset, family, rest length:
// 0 across, 1 down, 2 diagonal, 3 two across, 4 two down)
struct Neighbour {
  int dr, dc, family, rest;
};
inline constexpr std::array<Neighbour, 12> neighbours{{{0, 1, 0, 0}, {1, 0, 0, 1}, {0, -1, 0, 0}, {-1, 0, 0, 1},
                                                      {1, 1, 1, 2}, {1, -1, 1, 2}, {-1, -1, 1, 2}, {-1, 1, 1, 2},
                                                      {0, 2, 2, 3}, {2, 0, 2, 4}, {0, -2, 2, 3}, {-2, 0, 2, 4}}};

// the six triangles with a corner at node (r, c), in the order it sums their wind: (cell row offset, cell
// column offset, which of the cell's two triangles: 0 = (k, k + columns, k + 1), 1 = (k + columns,
// k + columns + 1, k + 1))
struct Triangle {
  int dr, dc, which;
};
inline constexpr std::array<Triangle, 6> triangles{{{-1, -1, 1}, {-1, 0, 0}, {-1, 0, 1}, {0, -1, 0}, {0, -1, 1}, {0, 0, 0}}};

// a step's numbers in T: the view's, the wind at the step's start (in double, then rounded), the step
template <class T>
struct Constants {
  int rows = 0, columns = 0;
  std::array<T, 5> rest{};       // across, down, diagonal, two across, two down
  std::array<T, 3> stiffness{};  // per family; a family switched off has `on` false
  std::array<bool, 3> on{};
  T damping = 0, node_mass = 0, drag = 0, g = 0, wind_coefficient = 0;
  Vec3<T> wind;
  int picked = -1;
  Vec3<T> pick_force;
  T sphere_radius = 0;
  Vec3<T> sphere_centre;
  bool ground = false;
  T ground_y = 0, friction = 0;
  T h = 0;
};

inline Eigen::Vector3d wind_at(const ClothGridView& view, double t) {
  return view.wind * (1 + view.gust_amplitude * std::sin(2 * std::numbers::pi * view.gust_frequency * t));
}

template <class T>
Constants<T> constants(const ClothGridView& view, double t, double h) {
  const auto f = [](double value) { return static_cast<T>(value); };
  return {view.rows, view.columns,
          {f(view.across), f(view.down), f(std::sqrt(view.across * view.across + view.down * view.down)), f(2 * view.across), f(2 * view.down)},
          {f(view.stiffness[0]), f(view.stiffness[1]), f(view.stiffness[2])}, view.family, f(view.damping), f(view.node_mass), f(view.drag),
          f(view.g), f(view.wind_coefficient), vec3<T>(wind_at(view, t)), view.picked, vec3<T>(view.pick_force), f(view.sphere_radius),
          vec3<T>(view.sphere_centre), view.ground, f(view.ground_y), f(view.friction), f(h)};
}

// the acceleration of free node (r, c) of grid-ordered positions x and velocities v (a pinned node's
// velocity 0)
template <class T>
Vec3<T> acceleration(const Constants<T>& k, const Vec3<T>* x, const Vec3<T>* v, int r, int c) {
  const int p = r * k.columns + c;
  Vec3<T> f;
  for (const Neighbour& n : neighbours) {
    const int rq = r + n.dr, cq = c + n.dc;
    if (!k.on[n.family] || rq < 0 || rq >= k.rows || cq < 0 || cq >= k.columns) continue;
    const int q = rq * k.columns + cq;
    f = f + spring_force(x[q] - x[p], v[q] - v[p], k.rest[n.rest], k.stiffness[n.family], k.damping);
  }
  if (k.wind_coefficient != 0)
    for (const Triangle& t : triangles) {
      const int rc = r + t.dr, cc = c + t.dc;
      if (rc < 0 || rc + 1 >= k.rows || cc < 0 || cc + 1 >= k.columns) continue;
      const int a = rc * k.columns + cc;
      const std::array<int, 3> corner = t.which == 0 ? std::array{a, a + k.columns, a + 1} : std::array{a + k.columns, a + k.columns + 1, a + 1};
      f = f + wind_share(area_vector(x[corner[0]], x[corner[1]], x[corner[2]]), mean_velocity(v[corner[0]], v[corner[1]], v[corner[2]]),
                         k.wind, k.wind_coefficient);
    }
  if (p == k.picked) f = f + k.pick_force;
  Vec3<T> a = f / k.node_mass - k.drag * v[p];
  a.y = a.y - k.g;
  return a;
}

// a node inside the sphere or below the ground put back on its surface, its approach stopped (the model's
// project)
template <class T>
void collide(const Constants<T>& k, Vec3<T>& x, Vec3<T>& v) {
  if (k.sphere_radius > 0) {
    const Vec3<T> offset = x - k.sphere_centre;
    const T distance = norm(offset);
    if (distance < k.sphere_radius && distance > 0) {
      const Vec3<T> n = offset / distance;
      x = k.sphere_centre + k.sphere_radius * n;
      if (dot(v, n) < 0) v = collision_response(v, n, T(0), k.friction);
    }
  }
  if (k.ground && x.y < k.ground_y) {
    x.y = k.ground_y;
    if (v.y < 0) v = collision_response(v, Vec3<T>{0, 1, 0}, T(0), k.friction);
  }
}

// every grid node's place and velocity, row-major (pinned nodes at their start, at rest)
template <class T>
struct State {
  std::vector<Vec3<T>> x, v;
};

// one symplectic Euler step of every free node, v1 = v + h a(t, x, v), x1 = x + h v1, then the obstacles
// (the integrator's step and the model's project): gpu-cloth's pass, on the CPU. Pinned nodes
// (free_index -1) are copied
template <class T>
void step(const Constants<T>& k, std::span<const int> free_index, const State<T>& in, State<T>& out) {
  out.x.resize(in.x.size());
  out.v.resize(in.v.size());
  for (int r = 0; r < k.rows; ++r)
    for (int c = 0; c < k.columns; ++c) {
      const int p = r * k.columns + c;
      if (free_index[p] < 0) {
        out.x[p] = in.x[p];
        out.v[p] = in.v[p];
        continue;
      }
      Vec3<T> v1 = in.v[p] + k.h * acceleration(k, in.x.data(), in.v.data(), r, c);
      Vec3<T> x1 = in.x[p] + k.h * v1;
      collide(k, x1, v1);
      out.x[p] = x1;
      out.v[p] = v1;
    }
}

// y's free nodes spread over the grid
template <class T>
State<T> spread(const ClothGridView& view, const Eigen::VectorXd& y) {
  const size_t nodes = view.start.size();
  const Eigen::Index free = y.size() / 6;
  State<T> s{std::vector<Vec3<T>>(nodes), std::vector<Vec3<T>>(nodes)};
  for (size_t k = 0; k < nodes; ++k) {
    const int i = view.free_index[k];
    s.x[k] = i < 0 ? vec3<T>(view.start[k]) : vec3<T>(y.segment<3>(3 * i));
    if (i >= 0) s.v[k] = vec3<T>(y.segment<3>(3 * (free + i)));
  }
  return s;
}

// the grid's free nodes gathered into y (sized already)
template <class T>
void gather(const ClothGridView& view, const State<T>& s, Eigen::VectorXd& y) {
  const Eigen::Index free = y.size() / 6;
  for (size_t k = 0; k < view.start.size(); ++k)
    if (const int i = view.free_index[k]; i >= 0) {
      y.segment<3>(3 * i) << s.x[k].x, s.x[k].y, s.x[k].z;
      y.segment<3>(3 * (free + i)) << s.v[k].x, s.v[k].y, s.v[k].z;
    }
}

}  // namespace stepwise::cloth_grid
