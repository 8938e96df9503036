// The pendulum's f (seeds: the pendulum), y = (theta, omega):
//   dtheta/dt = omega,  domega/dt = -w^2 sin theta  (w^2 theta in the small-angle model),
// as the model computes it (models/pendulum.cpp) and as the fixed-step methods call it inline when the model
// offers it (solvers/capabilities/inline_rhs.hpp).
#pragma once

#include <cmath>

namespace stepwise {

struct PendulumRhs {
  static constexpr int size = 2;
  double w2 = 1;             // g / L (1/s^2)
  bool small_angle = false;  // sin theta taken as theta

  template <class T>
  void operator()(double /*t*/, const T* y, T* dydt) const {
    dydt[0] = y[1];
    dydt[1] = -w2 * (small_angle ? y[0] : std::sin(y[0]));
  }
};

}  // namespace stepwise
