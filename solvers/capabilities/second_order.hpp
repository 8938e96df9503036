// Capability: y = (x, v) with dx/dt = v, the layout symplectic steppers need (symplectic-euler, the
// mass-spring methods). A model offers it through OdeSystem::capability; a method asks for it with
// system.as<SecondOrderView>() and names it with needs_second_order.
#pragma once

#include <stepwise/solvers/ode_system.hpp>

#include <functional>

namespace stepwise {

struct SecondOrderView {
  int positions = 0;  // number of position coordinates n; y has 2n entries, x = y[0..n), v = y[n..2n)
  // a = dv/dt alone (n entries) where the model computes it cheaper than f (a particle system, a cloth);
  // empty: the second half of f (solvers/run_support.hpp's second_order_acceleration, which counts it)
  std::function<void(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> a)> acceleration;
  // where each acceleration entry depends only on the same entries of x and v (a force field without
  // interactions): a[0, count) for entries [first, first + count) from x and v over the same range, so a
  // stepper can sweep a large state once, in blocks that stay in cache, rather than in three passes; empty
  // otherwise. The stepper counts one evaluation of f per sweep
  std::function<void(double t, const double* x, const double* v, double* a, Eigen::Index first, Eigen::Index count)> local_acceleration;
};

inline const Requirement needs_second_order = needs<SecondOrderView>("a second-order model y = (x, v)");

}  // namespace stepwise
