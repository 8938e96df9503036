// The particle system's update against the memory bandwidth it is bound by, measured in the same run.
//
// A step of N particles in the force field must read and write every position and velocity: 6 doubles in,
// 6 out, 96 bytes per particle-step counted as STREAM counts (McCalpin 1995: the triad a = b + s c moves
// 24 bytes per element). The bound is the triad's bandwidth over 96 bytes, with the triad's three arrays
// as large together as the step's working set (state, next state, acceleration: 15 doubles per particle),
// so the default scene's 100 000 particles (12 MB, inside this machine's 32 MB L3) meet a cache-sized
// bound and 4 000 000 (480 MB) meet main memory. The step is the whole fixed-step loop of `stepwise run`
// with symplectic Euler, divergence test included.
//
// The repulsion's pairs: the cell list against all-pairs testing on the same points.
#include "models/cell_list.hpp"
#include "models/model.hpp"
#include "ratio_reporter.hpp"
#include "stream_triad.hpp"
#include "solvers/method_table.hpp"

#include <random>

namespace {

constexpr double bytes_per_particle_step = 96;  // 6 doubles read, 6 written
// steps per run: a run's first touch of its fresh state buffers (page faults) costs about as much as 40
// steps, so runs as long as a scene's keep it below a tenth of the time
constexpr int steps = 400;

// `steps` symplectic-Euler steps of range(0) particles, with the repulsion's stiffness range(1) (0: off)
void BM_particle_step(benchmark::State& state) {
  const auto n = static_cast<double>(state.range(0));
  const auto model = stepwise::make_model("particle-system", {{"count", n}, {"repulsion", static_cast<double>(state.range(1))}});
  const auto integrator = stepwise::make_integrator("symplectic-euler", stepwise::StepControl::fixed(1e-3));
  const Eigen::VectorXd y0 = model->initial_state();
  for (auto _ : state) {
    const auto r = integrator->integrate(*model, 0.0, y0, std::vector{steps * 1e-3});
    benchmark::DoNotOptimize(r.y_stop[0]);
  }
  state.counters["particle_steps"] = benchmark::Counter(n * steps * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_particle_step)->Args({100000, 0})->Args({4000000, 0})->Unit(benchmark::kMillisecond)->UseRealTime();

// a[i] = b[i] + s c[i] over arrays as large together as n particles' working set
void BM_triad(benchmark::State& state) { stepwise::bench::stream_triad(state, static_cast<Eigen::Index>(state.range(0)) * 5, 20); }
BENCHMARK(BM_triad)->Arg(100000)->Arg(4000000)->Unit(benchmark::kMillisecond)->UseRealTime();

// with the repulsion on: the pairs dominate, and the cell list keeps them O(N)
BENCHMARK(BM_particle_step)->Args({100000, 400})->Unit(benchmark::kMillisecond)->UseRealTime();

// n points of the default scene's density (100 000 in [-1, 1]^3), radius 0.05
std::vector<double> cloud(int n) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  const double side = std::cbrt(n / 1e5);
  std::vector<double> p(3 * static_cast<size_t>(n));
  for (auto& x : p) x = side * u(rng);
  return p;
}

void BM_pairs_cell_list(benchmark::State& state) {
  const auto p = cloud(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    stepwise::CellList cells;
    cells.build(p.data(), static_cast<int>(state.range(0)), 0.05);
    long pairs = 0;
    cells.for_each_pair([&](int, int, const Eigen::Vector3d&, double) { ++pairs; });
    benchmark::DoNotOptimize(pairs);
  }
}
BENCHMARK(BM_pairs_cell_list)->Arg(5000)->Arg(100000)->Unit(benchmark::kMillisecond);

void BM_pairs_all(benchmark::State& state) {
  const auto p = cloud(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    long pairs = 0;
    stepwise::for_each_pair_brute_force(p.data(), static_cast<int>(state.range(0)), 0.05,
                                        [&](int, int, const Eigen::Vector3d&, double) { ++pairs; });
    benchmark::DoNotOptimize(pairs);
  }
}
BENCHMARK(BM_pairs_all)->Arg(5000)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  using stepwise::bench::RateBound;
  return stepwise::bench::run_with_ratios(
      argc, argv, {{"BM_pairs_all/5000", "BM_pairs_cell_list/5000"}},
      {RateBound{"BM_particle_step/100000/0/real_time", "particle_steps", "BM_triad/100000/real_time", "bytes", bytes_per_particle_step},
       RateBound{"BM_particle_step/4000000/0/real_time", "particle_steps", "BM_triad/4000000/real_time", "bytes", bytes_per_particle_step}});
}
