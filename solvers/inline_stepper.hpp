// A fixed-step method's stepper on the model's f called inline (solvers/capabilities/inline_rhs.hpp) where the
// model offers it, else through the system for its size (make_sized). Stepper<N, F>: F the kernel, or void
// for the calls through the system; constructed as Stepper(system) or Stepper(system, kernel).
#pragma once

#include <stepwise/solvers/capabilities/inline_rhs.hpp>
#include <stepwise/solvers/fixed_step.hpp>
#include <stepwise/solvers/run_support.hpp>

#include <type_traits>
#include <variant>

namespace stepwise {

// a stepper's kernel member: the kernel, or nothing when it calls f through the system
struct ThroughSystem {};
template <class F>
using KernelOr = std::conditional_t<std::is_void_v<F>, ThroughSystem, F>;

template <template <int, class> class Stepper>
struct SteppingThroughSystem {
  template <int N>
  using type = Stepper<N, void>;
};

// Stepper(system, args..., kernel) on the inline f, else Stepper(system, args...) for the system's size; Base:
// the stepper's interface (FixedStepper, or AdaptiveStepper for the pairs)
template <template <int, class> class Stepper, class Base = FixedStepper, class... Args>
std::unique_ptr<Base> make_inline_or_sized(const CountedSystem& system, const Args&... args) {
  if (const auto* inline_rhs = system.as<InlineRhs>()) {
    auto made = std::visit(
        [&](const auto& f) -> std::unique_ptr<Base> {
          using F = std::decay_t<decltype(f)>;
          if (system.size() != F::size) return nullptr;
          return std::make_unique<Stepper<F::size, F>>(system, args..., f);
        },
        inline_rhs->f);
    if (made) return made;
  }
  return make_sized<SteppingThroughSystem<Stepper>::template type, Base>(system.size(), system, args...);
}

}  // namespace stepwise
