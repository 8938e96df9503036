// The projectile's f (seeds: particles in a force field), y = (x, y, vx, vy), with linear drag k:
//   dx/dt = vx,  dy/dt = vy,  dvx/dt = -k vx,  dvy/dt = -g - k vy,
// as the model computes it (models/projectile.cpp) and as the steppers call it inline when the model offers it
// (solvers/capabilities/inline_rhs.hpp).
#pragma once

namespace stepwise {

struct ProjectileRhs {
  static constexpr int size = 4;
  double g = 9.81;  // gravitational acceleration (m/s^2)
  double k = 0;     // drag per unit mass (1/s)

  template <class T>
  void operator()(double /*t*/, const T* y, T* dydt) const {
    dydt[0] = y[2];
    dydt[1] = y[3];
    dydt[2] = -k * y[2];
    dydt[3] = -g - k * y[3];
  }
};

}  // namespace stepwise
