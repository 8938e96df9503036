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

// f compiled from a scene's own equations (models/equations.cpp: C printed from the parsed formulas, loaded from
// a shared object): a plain function pointer and the parameters it reads. Called inline, a step makes an indirect
// call but no virtual one and no round trip through Eigen::Ref; sizes 2 to 4 (the shipped equation scenes;
// larger systems call through the system, where f's own cost dominates the call's)
template <int N>
struct NativeRhs {
  static constexpr int size = N;
  void (*f)(double t, const double* y, const double* p, double* dydt) = nullptr;
  const double* p = nullptr;
  void operator()(double t, const double* y, double* dydt) const { f(t, y, p, dydt); }
};

struct InlineRhs {
  // each kernel: `static constexpr int size` and `void operator()(double t, const double* y, double* dydt) const`
  std::variant<PendulumRhs, ProjectileRhs, FlowParticleRhs, NativeRhs<2>, NativeRhs<3>, NativeRhs<4>> f;
};

}  // namespace stepwise
