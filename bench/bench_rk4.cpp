// The hand-written fixed-step methods against Boost.Odeint's (the peer a C++ user would pick instead) on the
// pendulum, theta0 = 1, dt = 1e-3, 10 s: rk4, euler and symplectic-euler, each with the same number of RHS
// calls, the peer on a fixed-size std::array state (unrolled at compile time) and on a std::vector one (a
// run-time size, as a model behind a run-time interface has). Ours twice: on the pendulum model, whose f the
// steppers call inline (solvers/capabilities/inline_rhs.hpp), and on a system offering no inline f, as a
// user's own would (`_through`: every call through the virtual rhs).
#include "models/model.hpp"
#include "solvers/capabilities/inline_rhs.hpp"
#include "solvers/capabilities/second_order.hpp"
#include "ratio_reporter.hpp"
#include "users_pendulum.hpp"
#include "solvers/method_table.hpp"

#include <fmt/format.h>

#include <boost/numeric/odeint.hpp>

#include <array>
#include <cmath>
#include <utility>

namespace {

namespace odeint = boost::numeric::odeint;

constexpr double dt = 1e-3, t_end = 10.0, theta0 = 1.0, w2 = 9.81;

void run_stepwise(benchmark::State& state, const char* method, bool inline_f = true) {
  const auto model = stepwise::make_model("pendulum", {{"theta0", theta0}, {"g", w2}});
  const stepwise::bench::UsersPendulum users(w2);
  const stepwise::OdeSystem& system = inline_f ? static_cast<const stepwise::OdeSystem&>(*model) : users;
  const auto integrator = stepwise::make_integrator(method, stepwise::StepControl::fixed(dt));
  for (auto _ : state) {
    const auto r = integrator->solve(system, 0.0, model->initial_state(), std::vector{t_end});
    benchmark::DoNotOptimize(r.trajectory.y.back()[0]);
  }
}

template <class Stepper, class State>
void run_odeint(benchmark::State& state) {
  auto rhs = [](const State& y, State& f, double) {
    f[0] = y[1];
    f[1] = -w2 * std::sin(y[0]);
  };
  for (auto _ : state) {
    State y{theta0, 0.0};
    Stepper stepper;
    odeint::integrate_const(stepper, rhs, y, 0.0, t_end, dt);
    benchmark::DoNotOptimize(y[0]);
  }
}

// symplectic Euler on (theta, omega) as odeint splits it: dtheta/dt = omega, domega/dt = -w^2 sin theta
template <class Coordinate>
void run_odeint_symplectic(benchmark::State& state) {
  auto dq = [](const Coordinate& p, Coordinate& dqdt) { dqdt[0] = p[0]; };
  auto dp = [](const Coordinate& q, Coordinate& dpdt) { dpdt[0] = -w2 * std::sin(q[0]); };
  for (auto _ : state) {
    std::pair<Coordinate, Coordinate> y{Coordinate{theta0}, Coordinate{0.0}};
    odeint::symplectic_euler<Coordinate> stepper;
    odeint::integrate_const(stepper, std::make_pair(dq, dp), y, 0.0, t_end, dt);
    benchmark::DoNotOptimize(y.first[0]);
  }
}

using Array = std::array<double, 2>;
using Vector = std::vector<double>;

void BM_rk4_stepwise(benchmark::State& state) { run_stepwise(state, "rk4"); }
void BM_rk4_stepwise_through(benchmark::State& state) { run_stepwise(state, "rk4", false); }
void BM_rk4_odeint(benchmark::State& state) { run_odeint<odeint::runge_kutta4<Array>, Array>(state); }
void BM_rk4_odeint_dynamic(benchmark::State& state) { run_odeint<odeint::runge_kutta4<Vector>, Vector>(state); }
void BM_euler_stepwise(benchmark::State& state) { run_stepwise(state, "euler"); }
void BM_euler_stepwise_through(benchmark::State& state) { run_stepwise(state, "euler", false); }
void BM_euler_odeint(benchmark::State& state) { run_odeint<odeint::euler<Array>, Array>(state); }
void BM_euler_odeint_dynamic(benchmark::State& state) { run_odeint<odeint::euler<Vector>, Vector>(state); }
void BM_symplectic_euler_stepwise(benchmark::State& state) { run_stepwise(state, "symplectic-euler"); }
void BM_symplectic_euler_stepwise_through(benchmark::State& state) { run_stepwise(state, "symplectic-euler", false); }
void BM_symplectic_euler_odeint(benchmark::State& state) { run_odeint_symplectic<std::array<double, 1>>(state); }
void BM_symplectic_euler_odeint_dynamic(benchmark::State& state) { run_odeint_symplectic<Vector>(state); }
BENCHMARK(BM_rk4_stepwise);
BENCHMARK(BM_rk4_stepwise_through);
BENCHMARK(BM_rk4_odeint);
BENCHMARK(BM_rk4_odeint_dynamic);
BENCHMARK(BM_euler_stepwise);
BENCHMARK(BM_euler_stepwise_through);
BENCHMARK(BM_euler_odeint);
BENCHMARK(BM_euler_odeint_dynamic);
BENCHMARK(BM_symplectic_euler_stepwise);
BENCHMARK(BM_symplectic_euler_stepwise_through);
BENCHMARK(BM_symplectic_euler_odeint);
BENCHMARK(BM_symplectic_euler_odeint_dynamic);

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::pair<std::string, std::string>> ratios;
  for (const char* method : {"rk4", "euler", "symplectic_euler"})
    for (const char* ours : {"stepwise", "stepwise_through"})
      for (const char* peer : {"odeint", "odeint_dynamic"})
        ratios.emplace_back(fmt::format("BM_{}_{}", method, ours), fmt::format("BM_{}_{}", method, peer));
  return stepwise::bench::run_with_ratios(argc, argv, ratios);
}
