// Capability: f as a formula from kernels/ of a small state whose size is known at compile time, which a
// fixed-step method may call inline rather than through OdeSystem::rhs. On the pendulum the virtual call and
// the stage's round trip through memory cost as much as the method's own arithmetic (bench_rk4: rk4 took 1.4-1.5
// times Boost.Odeint's runge_kutta4 on a std::array state, whose f the compiler inlines). A model offers it
// through OdeSystem::capability beside its rhs, which must compute the same formula (the model calls the kernel
// itself); a method asks with system.as<InlineRhs>() and counts the calls it makes (Stats::rhs_evals).
#pragma once

#include "kernels/flow_particle.hpp"
#include "kernels/pendulum.hpp"
#include "kernels/projectile.hpp"
#include "solvers/ode_system.hpp"

#include <variant>

namespace stepwise {

struct InlineRhs {
  // each kernel: `static constexpr int size` and `void operator()(double t, const double* y, double* dydt) const`
  std::variant<PendulumRhs, ProjectileRhs, FlowParticleRhs> f;
};

}  // namespace stepwise
