// Capability: f as a formula from kernels/ of a small state whose size is known at compile time, which a
// fixed-step method may call inline rather than through OdeSystem::rhs. On the pendulum the virtual call and
// the stage's round trip through memory cost as much as the method's own arithmetic (bench_rk4: rk4 took 1.4-1.5
// times Boost.Odeint's runge_kutta4 on a std::array state, whose f the compiler inlines). A model offers it
// through OdeSystem::capability beside its rhs, which must compute the same formula (the model calls the kernel
// itself); which models' kernels may be offered is kernels/inline_kernels.hpp's list, kept beside the kernels,
// so a model joins the path without an edit here; a method asks with system.as<InlineRhs>() and counts the calls
// it makes (Stats::rhs_evals).
#pragma once

#include <stepwise/kernels/inline_kernels.hpp>
#include <stepwise/solvers/ode_system.hpp>

#include <type_traits>
#include <utility>
#include <variant>

namespace stepwise {

// f compiled from a scene's own equations (models/equations/: C printed from the parsed formulas, loaded from
// a shared object): a plain function pointer and the parameters it reads, sizes 2 to 4 (the shipped equation
// scenes; larger systems call through the system, where f's own cost dominates the call's). The function takes
// the state as N arguments and returns f as a struct of N doubles, so that the state and f pass in registers
// (the x86-64 and AArch64 ABIs: up to 8 doubles in, 2 out, where a struct of 2 doubles is returned): the stepper
// keeps its stages in registers as it does around an inlined kernel, rather than storing each for f to load
template <int N>
struct NativeValues {
  double v[N];
};
template <int N, class = std::make_index_sequence<N>>
struct NativeValuesFn;
template <int N, size_t... I>
struct NativeValuesFn<N, std::index_sequence<I...>> {
  using type = NativeValues<N> (*)(double t, std::conditional_t<I < N, double, void>... y, const double* p);
};

template <int N>
struct NativeRhs {
  static constexpr int size = N;
  typename NativeValuesFn<N>::type f = nullptr;
  const double* p = nullptr;
  // f's values stored one by one from the registers they return in: a copy of the returned struct was vectorised
  // into a 16-byte load of its two 8-byte halves spilled to the stack, a store-to-load forwarding stall that took
  // 65% of the call's samples (perf: tsitouras54 and verner98 on the pendulum)
  __attribute__((always_inline)) void operator()(double t, const double* y, double* dydt) const {
    [&]<size_t... I>(std::index_sequence<I...>) __attribute__((always_inline)) {
      const NativeValues<N> r = f(t, y[I]..., p);
      const auto from_register = [](double x) __attribute__((always_inline)) {
        asm("" : "+x"(x));  // GCC and clang: a value in an SSE register, so no pass reads the struct back from memory
        return x;
      };
      ((dydt[I] = from_register(r.v[I])), ...);
    }(std::make_index_sequence<N>{});
  }
};

// one variant of the models' kernels (kernels/inline_kernels.hpp's list) and the compiled equations' f
template <class List, class... More>
struct KernelVariant;
template <class... Kernels, class... More>
struct KernelVariant<KernelList<Kernels...>, More...> {
  using type = std::variant<Kernels..., More...>;
};

struct InlineRhs {
  // each kernel: `static constexpr int size` and `void operator()(double t, const double* y, double* dydt) const`
  KernelVariant<ModelKernels, NativeRhs<2>, NativeRhs<3>, NativeRhs<4>>::type f;
};

}  // namespace stepwise
