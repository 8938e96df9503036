// Capability: particles held by distance constraints, the structure position-based methods step (pbd, xpbd).
// y = (x, v) as SecondOrderView lays it out, x the particles' coordinates `dimension` at a time. Constraint j
// holds |x_a - x_b| = length (b < 0: x_a at `anchor`), with compliance alpha (m/N, the inverse of a spring's
// stiffness; 0: inextensible). `external` is the acceleration without the constraints' forces (gravity), which
// a position-based method integrates before it projects. A model offers it through OdeSystem::capability beside
// its own f, the constrained equations of motion an ODE method steps.
#pragma once

#include <stepwise/solvers/ode_system.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

namespace stepwise {

struct DistanceConstraint {
  int a = 0, b = -1;  // the particles; b < 0: a fixed anchor
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  double length = 1;      // m
  double compliance = 0;  // alpha, m/N
};

struct DistanceConstraints {
  int dimension = 2;
  std::vector<double> inverse_mass;  // 1/kg a particle; 0: pinned
  std::vector<DistanceConstraint> constraints;
  // the acceleration of every coordinate (n entries) without the constraints' forces
  std::function<void(double t, const double* x, const double* v, double* a)> external;

  int particles() const { return static_cast<int>(inverse_mass.size()); }

  // C_j(x) = |x_a - x_b| - length, and its unit direction (x_a - x_b) / |x_a - x_b| in `direction` (dimension
  // entries; zero where the two points coincide)
  double violation(const DistanceConstraint& c, const double* x, double* direction) const {
    double r2 = 0;
    for (int k = 0; k < dimension; ++k) {
      const double d = x[c.a * dimension + k] - (c.b < 0 ? c.anchor[k] : x[c.b * dimension + k]);
      direction[k] = d;
      r2 += d * d;
    }
    const double r = std::sqrt(r2);
    for (int k = 0; k < dimension; ++k) direction[k] = r > 0 ? direction[k] / r : 0;
    return r - c.length;
  }

  // the rigid constraints alone (compliance 0), the ones a method must meet exactly (RATTLE's SHAKE, the
  // projection); the compliant ones are springs, whose forces compliant_forces() gives
  DistanceConstraints rigid() const {
    DistanceConstraints r{dimension, inverse_mass, {}, external};
    for (const auto& c : constraints)
      if (c.compliance == 0) r.constraints.push_back(c);
    return r;
  }
  // a += W (the compliant constraints' forces): constraint j pulls with lambda_j = -C_j / alpha_j along its
  // direction (Hooke's law, stiffness 1 / alpha); the rigid ones add nothing
  void add_compliant_forces(const double* x, double* a) const {
    double n[3] = {0, 0, 0};
    for (const auto& c : constraints) {
      if (c.compliance == 0) continue;
      const double lambda = -violation(c, x, n) / c.compliance;
      for (int k = 0; k < dimension; ++k) {
        a[c.a * dimension + k] += inverse_mass[static_cast<size_t>(c.a)] * lambda * n[k];
        if (c.b >= 0) a[c.b * dimension + k] -= inverse_mass[static_cast<size_t>(c.b)] * lambda * n[k];
      }
    }
  }

  // the largest |C_j(x)| / length_j: the drift from the constraint manifold (summary.json's constraint_drift)
  double drift(const double* x) const {
    double worst = 0, direction[3] = {0, 0, 0};
    for (const auto& c : constraints) worst = std::max(worst, std::abs(violation(c, x, direction)) / c.length);
    return worst;
  }
};

// Baumgarte stabilisation of a constrained model's equations of motion (its `baumgarte` flag): the multipliers
// hold g'' + 2 w g' + w^2 g = 0 rather than g'' = 0, a critically damped return of any drift, at w = 10 sqrt(g / l)
// for the shortest link l: ten times the motion's own rate, so a drift is gone within a tenth of a swing, while
// w dt stays below 1 (explicit methods stable) for steps up to a tenth of the swing's time scale
inline double baumgarte_rate(double gravity, double shortest_link) { return 10 * std::sqrt(gravity / shortest_link); }

inline const Requirement needs_distance_constraints =
    needs<DistanceConstraints>("a scene whose particles are held by distance constraints (pendulum-cartesian)");

}  // namespace stepwise
