// Hand-written rk4 against Boost.Odeint's runge_kutta4 (a peer a user might pick instead): the pendulum,
// theta0 = 1, dt = 1e-3, 10 s, both with fixed steps and the same number of RHS calls.
#include "models/model.hpp"
#include "ratio_reporter.hpp"
#include "solvers/method_table.hpp"

#include <boost/numeric/odeint.hpp>

#include <array>
#include <cmath>

namespace {

constexpr double dt = 1e-3, t_end = 10.0;

void BM_rk4_stepwise(benchmark::State& state) {
  const auto model = stepwise::make_model("pendulum", {{"theta0", 1.0}});
  stepwise::StepControl control;
  control.dt = dt;
  const auto integrator = stepwise::make_integrator("rk4", control);
  for (auto _ : state) {
    const auto r = integrator->integrate(*model, 0.0, model->initial_state(), std::vector{t_end});
    benchmark::DoNotOptimize(r.trajectory.y.back()[0]);
  }
}
BENCHMARK(BM_rk4_stepwise);

template <class State>
void run_odeint(benchmark::State& state) {
  const double w2 = 9.81;
  auto rhs = [w2](const State& y, State& f, double) {
    f[0] = y[1];
    f[1] = -w2 * std::sin(y[0]);
  };
  for (auto _ : state) {
    State y{1.0, 0.0};
    boost::numeric::odeint::runge_kutta4<State> stepper;
    boost::numeric::odeint::integrate_const(stepper, rhs, y, 0.0, t_end, dt);
    benchmark::DoNotOptimize(y[0]);
  }
}

// odeint on a fixed-size state, unrolled at compile time
void BM_rk4_odeint(benchmark::State& state) { run_odeint<std::array<double, 2>>(state); }
BENCHMARK(BM_rk4_odeint);

// the same peer on a run-time-sized state, as a model behind a run-time interface has
void BM_rk4_odeint_dynamic(benchmark::State& state) { run_odeint<std::vector<double>>(state); }
BENCHMARK(BM_rk4_odeint_dynamic);

}  // namespace

int main(int argc, char** argv) {
  return stepwise::bench::run_with_ratios(argc, argv,
                                          {{"BM_rk4_stepwise", "BM_rk4_odeint"}, {"BM_rk4_stepwise", "BM_rk4_odeint_dynamic"}});
}
