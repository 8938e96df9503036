#include "springs.hpp"

namespace stepwise {

namespace {

// x_b - x_a (the anchor for a pinned spring)
Eigen::Vector3d span_of(const Spring& s, const double* x) {
  return Eigen::Map<const Eigen::Vector3d>(x + 3 * s.b) - (s.a < 0 ? s.anchor : Eigen::Vector3d(Eigen::Map<const Eigen::Vector3d>(x + 3 * s.a)));
}

// v_b - v_a (an anchor does not move)
Eigen::Vector3d closing_of(const Spring& s, const double* v) {
  const Eigen::Map<const Eigen::Vector3d> vb(v + 3 * s.b);
  return s.a < 0 ? Eigen::Vector3d(vb) : Eigen::Vector3d(vb - Eigen::Map<const Eigen::Vector3d>(v + 3 * s.a));
}

}  // namespace

void add_spring_forces(std::span<const Spring> springs, const double* x, const double* v, double* f) {
  for (const Spring& s : springs) {
    const Eigen::Vector3d r = span_of(s, x), w = closing_of(s, v);
    const double length = r.norm();
    const Eigen::Vector3d u = r / length;
    const Eigen::Vector3d force = (s.stiffness * (length - s.rest) + s.damping * u.dot(w)) * u;
    Eigen::Map<Eigen::Vector3d>(f + 3 * s.b) -= force;
    if (s.a >= 0) Eigen::Map<Eigen::Vector3d>(f + 3 * s.a) += force;
  }
}

double spring_energy(std::span<const Spring> springs, const double* x) {
  double e = 0;
  for (const Spring& s : springs) {
    const double stretch = span_of(s, x).norm() - s.rest;
    e += s.stiffness * stretch * stretch / 2;
  }
  return e;
}

void add_spring_jacobian(std::span<const Spring> springs, const double* x, const double* v, double scale, Eigen::Index row0,
                         Eigen::Index x0, Eigen::Index v0, std::vector<Eigen::Triplet<double>>& out) {
  for (const Spring& s : springs) {
    const Eigen::Vector3d r = span_of(s, x), w = closing_of(s, v);
    const double length = r.norm();
    const Eigen::Vector3d u = r / length;
    const Eigen::Matrix3d uu = u * u.transpose(), across = Eigen::Matrix3d::Identity() - uu;
    const double tension = s.stiffness * (length - s.rest) + s.damping * u.dot(w);
    const Eigen::Matrix3d dr = s.stiffness * uu + tension / length * across + s.damping / length * u * (across * w).transpose();
    const Eigen::Matrix3d dw = s.damping * uu;
    // F acts on a (+) and b (-); it depends on r and w through x_b, v_b (+) and x_a, v_a (-)
    const auto block = [&](int node, int by, double sign) {
      if (node < 0 || by < 0) return;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          out.emplace_back(row0 + 3 * node + i, x0 + 3 * by + j, sign * scale * dr(i, j));
          out.emplace_back(row0 + 3 * node + i, v0 + 3 * by + j, sign * scale * dw(i, j));
        }
    };
    block(s.a, s.b, 1);
    block(s.a, s.a, -1);
    block(s.b, s.b, -1);
    block(s.b, s.a, 1);
  }
}

}  // namespace stepwise
