// Cost of one right-hand-side call through the OdeSystem interface (virtual call, Eigen::Ref arguments)
// against calling the same pendulum function directly.
#include "models/model.hpp"
#include "ratio_reporter.hpp"

#include <cmath>

namespace {

void pendulum_direct(double w2, const Eigen::VectorXd& y, Eigen::VectorXd& f) {
  f[0] = y[1];
  f[1] = -w2 * std::sin(y[0]);
}

void BM_rhs_direct(benchmark::State& state) {
  Eigen::VectorXd y(2), f(2);
  y << 1.0, 0.0;
  const double w2 = 9.81;
  for (auto _ : state) {
    pendulum_direct(w2, y, f);
    benchmark::DoNotOptimize(f.data());
    y[0] += 1e-12;
  }
}
BENCHMARK(BM_rhs_direct);

void BM_rhs_interface(benchmark::State& state) {
  const auto model = stepwise::make_model("pendulum");
  const stepwise::OdeSystem& system = *model;
  Eigen::VectorXd y(2), f(2);
  y << 1.0, 0.0;
  for (auto _ : state) {
    system.rhs(0.0, y, f);
    benchmark::DoNotOptimize(f.data());
    y[0] += 1e-12;
  }
}
BENCHMARK(BM_rhs_interface);

}  // namespace

int main(int argc, char** argv) {
  return stepwise::bench::run_with_ratios(argc, argv, {{"BM_rhs_interface", "BM_rhs_direct"}});
}
