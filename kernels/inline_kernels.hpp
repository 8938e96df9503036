// The models' kernels on the fixed-step methods' inline fast path (solvers/capabilities/inline_rhs.hpp). A model
// puts its f on the path here, beside the kernel: it writes f as a kernel in kernels/ (`static constexpr int
// size` and `void operator()(double t, const double* y, double* dydt) const`), names it in this list, and offers
// it as an InlineRhs through its capability(); solvers/ is generic over the list and needs no edit. A kernel's
// steppers are compiled for it (inlined), so each one named here adds code to every fixed-step method.
#pragma once

#include <stepwise/kernels/flow_particle.hpp>
#include <stepwise/kernels/pendulum.hpp>
#include <stepwise/kernels/projectile.hpp>

namespace stepwise {

template <class... Kernels>
struct KernelList {};

using ModelKernels = KernelList<PendulumRhs, ProjectileRhs, FlowParticleRhs>;

}  // namespace stepwise
