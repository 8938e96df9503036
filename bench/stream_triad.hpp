// The memory bound the benches measure their kernels against: McCalpin's STREAM triad (1995),
// a[i] = b[i] + s c[i], counted as STREAM counts it, 24 bytes per element (the store's read of the line
// it writes not counted). One definition for every bench that pairs a kernel with it in one run.
#pragma once

#include <benchmark/benchmark.h>

#include <Eigen/Core>

namespace stepwise::bench {

// `repeats` triads per iteration over three arrays of `length` doubles; sets the "bytes" rate counter
inline void stream_triad(benchmark::State& state, Eigen::Index length, int repeats = 1) {
  Eigen::VectorXd a = Eigen::VectorXd::Zero(length), b = Eigen::VectorXd::Constant(length, 1.0), c = Eigen::VectorXd::Constant(length, 2.0);
  const double s = 3.0;
  for (auto _ : state) {
    for (int k = 0; k < repeats; ++k) {
      a = b + s * c;
      benchmark::DoNotOptimize(a.data());
      benchmark::ClobberMemory();
    }
  }
  state.counters["bytes"] = benchmark::Counter(24.0 * static_cast<double>(length) * repeats * static_cast<double>(state.iterations()),
                                               benchmark::Counter::kIsRate);
}

}  // namespace stepwise::bench
