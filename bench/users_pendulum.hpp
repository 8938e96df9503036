// The pendulum as a user's own system written in C++ would be: its f (the model's formula, kernels/pendulum.hpp)
// through the virtual rhs only, no inline f offered; y = (x, v) for symplectic Euler. bench_rk4 and
// bench_equations time the project's methods on it beside the built-in model.
#pragma once

#include "kernels/pendulum.hpp"
#include "solvers/capabilities/second_order.hpp"
#include "solvers/ode_system.hpp"

namespace stepwise::bench {

class UsersPendulum final : public OdeSystem {
 public:
  explicit UsersPendulum(double w2) : f_{w2} {}
  int size() const override { return 2; }
  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override { f_(t, y.data(), dydt.data()); }
  bool autonomous() const override { return true; }
  const void* capability(const std::type_info& type) const override { return offer(type, second_order_); }

 private:
  PendulumRhs f_;
  SecondOrderView second_order_{1};
};

}  // namespace stepwise::bench
