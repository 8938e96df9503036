// The fluid's costs against what bounds them, measured in the same run:
//  - the pseudo-spectral right-hand side against one of FFTW's 2D real-to-complex transforms of the same grid.
//    Without density f transforms u and v in (2), takes the four derivatives and u, v back to the grid (6
//    inverses), and the two products forward (2): ten transforms, and pointwise work between them; so f should
//    cost about ten transforms, more by what the pointwise passes add.
//  - a step of stable-fluids (Taylor-Green: u, v and the density field it always carries) against the memory
//    bandwidth of a STREAM triad (McCalpin 1995: a = b + s c, 24 bytes per element) on arrays of the grid's
//    size. Counted as STREAM counts, one pass per array the step streams: the copy of the state (48 bytes a
//    cell), the trace (read u, v, write the departure points: 32), three advections (read the departure points,
//    write the value: 24 each, the gathers from cache), u and v forward (16 each, a mode being half a value's
//    8 bytes per cell, read and written once), diffusion and projection in the modes (64), u and v back (16
//    each), and the divergence test's pass (24): 328 bytes a cell if each FFT were a single pass. FFTW's large
//    transforms are not, so the step is expected below the bound; how far is what this measures. The step's
//    time is also put against one forward transform's: its four transforms (u, v forward and back) and
//    three gathers (u, v, density at the departure points) are what it does; `steps` steps an iteration.
#include "models/model.hpp"
#include "ratio_reporter.hpp"
#include "stream_triad.hpp"
#include "run/measure.hpp"
#include "solvers/periodic_fft.hpp"

#include <fmt/format.h>

#include <cmath>

namespace {

constexpr double step_bytes_per_cell = 328;
constexpr int steps = 8;  // stable-fluids steps per iteration, one run (its set-up, a few passes over the state, is in it)

std::unique_ptr<stepwise::Model> vortex(int n) { return stepwise::make_model("taylor-green", {{"size", n}, {"viscosity", 1e-3}}); }

// one forward transform of an n^2 field
void BM_fft_forward(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const stepwise::PeriodicFft fft(n, 1.0);
  const Eigen::VectorXd grid = Eigen::VectorXd::Random(static_cast<Eigen::Index>(n) * n);
  std::vector<stepwise::PeriodicFft::Complex> modes(fft.modes());
  for (auto _ : state) {
    fft.forward(grid.data(), modes.data());
    benchmark::DoNotOptimize(modes.data());
  }
}

// f of the Taylor-Green vortex through the OdeSystem interface
void BM_fluid_rhs(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto model = vortex(n);
  const Eigen::VectorXd y = model->initial_state();
  Eigen::VectorXd f(y.size());
  for (auto _ : state) {
    model->rhs(0.0, y, f);
    benchmark::DoNotOptimize(f.data());
  }
}

// `steps` steps of stable-fluids at CFL 1, by run's path
void BM_stable_fluids(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto model = vortex(n);
  const double h = 1.0 / n;
  stepwise::StepControl control = stepwise::StepControl::fixed(h);
  control.observe = [](const Eigen::VectorXd&) { return Eigen::VectorXd(); };  // no summary (its transforms) at the outputs
  for (auto _ : state) {
    const auto m = stepwise::run_and_measure(*model, "stable-fluids", control, steps * h, steps * h);
    benchmark::DoNotOptimize(m.result.y_stop.data());
  }
  state.counters["cells"] = benchmark::Counter(static_cast<double>(n) * n * steps * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

// a[i] = b[i] + s c[i] over three arrays of range(0)^2
void BM_triad(benchmark::State& state) { stepwise::bench::stream_triad(state, state.range(0) * state.range(0)); }

const std::vector<int> sizes{256, 1024, 2048};
void grids(benchmark::internal::Benchmark* b) {
  for (const int n : sizes) b->Arg(n);
}
BENCHMARK(BM_fft_forward)->Apply(grids)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_fluid_rhs)->Apply(grids)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_stable_fluids)->Apply(grids)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_triad)->Apply(grids)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::pair<std::string, std::string>> pairs;
  std::vector<stepwise::bench::RateBound> bounds;
  for (const int n : sizes) {
    pairs.emplace_back(fmt::format("BM_fluid_rhs/{}", n), fmt::format("BM_fft_forward/{}", n));
    pairs.emplace_back(fmt::format("BM_stable_fluids/{}", n), fmt::format("BM_fft_forward/{}", n));
    bounds.push_back({fmt::format("BM_stable_fluids/{}", n), "cells", fmt::format("BM_triad/{}", n), "bytes", step_bytes_per_cell});
  }
  return stepwise::bench::run_with_ratios(argc, argv, pairs, bounds);
}
