// The flow field's f (seeds: particles in a velocity field), a particle carried by v(x, y) = (x, sin y):
//   dx/dt = x,  dy/dt = sin y,
// as the model computes it (models/flow_particle.cpp) and as the steppers call it inline when the model offers
// it (solvers/capabilities/inline_rhs.hpp).
#pragma once

#include <cmath>

namespace stepwise {

struct FlowParticleRhs {
  static constexpr int size = 2;

  template <class T>
  void operator()(double /*t*/, const T* p, T* dpdt) const {
    dpdt[0] = p[0];
    dpdt[1] = std::sin(p[1]);
  }
};

}  // namespace stepwise
