// The seeds' height-field update against the memory bandwidth it is bound by, measured in the same run;
// its OpenMP and temporally blocked forms against it; the method of lines through CVODE against the
// three-level scheme at equal accuracy.
//
// A step reads z^k and z^{k-1} and writes z^{k+1}: 24 bytes per cell as STREAM counts them (McCalpin
// 1995: the triad a = b + s c moves 24 bytes per element), so the bound is the triad's bandwidth over 24
// bytes, with the triad's three arrays as large as three grids: 256^2 (1.5 MB, in L2 and L3), 1024^2
// (24 MB, in this machine's 32 MB L3), 4096^2 (384 MB, main memory). The step writes z^{k+1} over z^{k-1}
// (wave_step.hpp), so its real traffic is those 24 bytes where the triad's is 32 (its store first reads
// the line it writes), and it prefetches in software where the triad relies on the hardware's: past the
// caches it can pass the triad's rate. Temporal blocking does 8 steps per pass of a wavefront that keeps
// its rows in cache, so it passes the streaming rate again; it is bitwise the plain loop (test_wave).
#include "models/height_field.hpp"
#include "ratio_reporter.hpp"
#include "stream_triad.hpp"
#include "solvers/gpu/gpu_wave.hpp"
#include "solvers/wave_step.hpp"
#include "run/measure.hpp"
#include "verification/wave_modes.hpp"

#include <fmt/format.h>

#include <array>

namespace {

constexpr double bytes_per_cell = 24;
constexpr int steps = 8;  // steps per iteration, the blocked kernel's steps per pass

struct Grids {
  explicit Grids(int n)
      : n(n), z_prev(stepwise::random_wave_field(n, 1, 1)), z(stepwise::random_wave_field(n, 1, 2)) {}
  int n;
  Eigen::VectorXd z_prev, z;
  stepwise::WaveCoefficients k = stepwise::wave_coefficients({n, 0.01, 1.0, 0.0}, 0.005);  // neutral: |r| = 1
};

void count_cells(benchmark::State& state, int n) {
  const double interior = static_cast<double>(n - 2) * (n - 2);
  state.counters["cells"] = benchmark::Counter(interior * steps * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

// range(0)^2 grid, range(1) threads: the plain loop, a step a pass
void BM_wave_step(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)), threads = static_cast<int>(state.range(1));
  Grids g(n);
  for (auto _ : state) {
    for (int s = 0; s < steps; ++s) {
      stepwise::wave_step(g.k, n, g.z_prev.data(), g.z.data(), threads);
      g.z_prev.swap(g.z);
    }
    benchmark::DoNotOptimize(g.z.data());
  }
  count_cells(state, n);
}

// the same 8 steps in one pass of temporal blocking (a wavefront, pipelined over the threads)
void BM_wave_blocked(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)), threads = static_cast<int>(state.range(1));
  Grids g(n);
  for (auto _ : state) {
    stepwise::wave_steps_blocked(g.k, n, steps, g.z_prev.data(), g.z.data(), threads);
    benchmark::DoNotOptimize(g.z.data());
  }
  count_cells(state, n);
}

// the same steps as passes on the GL's device (llvmpipe here, its threads LP_NUM_THREADS, by default one per
// core; a GPU through EGL with STEPWISE_GPU_BACKEND=egl, as the methods), in float32, finished before the clock
// stops: range(1) 0 the fragment pass (gpu-wave), 1 the compute pass with its shared tile (gpu-wave-compute),
// 2 the compute pass reading every z from the buffer, 3 the compute pass taking four steps a dispatch on a tile
// with a four-cell halo
void BM_gpu_wave(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  static const std::unique_ptr<stepwise::gl::Context> context = stepwise::gl::make_context(stepwise::gpu::backend());
  Grids g(n);
  const auto pass = state.range(1) == 0 ? stepwise::gpu::Pass::fragment : stepwise::gpu::Pass::compute;
  using stepwise::gpu::Tiling;
  const Tiling tiling = std::array{Tiling::tile, Tiling::tile, Tiling::none, Tiling::four_steps}[static_cast<size_t>(state.range(1))];
  stepwise::gpu::GpuWave gpu(*context, n, stepwise::to_float(g.k), pass, tiling);
  gpu.upload(g.z_prev.cast<float>(), g.z.cast<float>());
  for (auto _ : state) {
    gpu.step(steps);
    gpu.finish();
  }
  count_cells(state, n);
  state.SetLabel(fmt::format("{}, {}", std::array{"fragment", "compute, tiled", "compute, untiled", "compute, four steps a dispatch"}[static_cast<size_t>(state.range(1))],
                             context->description()));
}

// the bound a pass's memory traffic has: a device-to-device copy of a grid's plane (n^2 vec4s) between two
// storage buffers, its bytes read and written counted (a pass reads one plane and writes one)
void BM_gpu_copy(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  static const std::unique_ptr<stepwise::gl::Context> context = stepwise::gl::make_context(stepwise::gpu::backend());
  context->make_current();
  const stepwise::gl::Gl& gl = context->gl();
  const auto bytes = static_cast<GLsizeiptr>(16) * n * n;
  GLuint buffers[2] = {0, 0};
  gl.CreateBuffers(2, buffers);
  for (const GLuint b : buffers) gl.NamedBufferStorage(b, bytes, nullptr, 0);
  for (auto _ : state) {
    gl.CopyNamedBufferSubData(buffers[0], buffers[1], 0, 0, bytes);
    gl.Finish();
  }
  gl.DeleteBuffers(2, buffers);
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * 2 * static_cast<int64_t>(bytes));
  state.SetLabel(context->description());
}

// the transfers a run adds to the passes, counted apart from them: range(1) 0 both levels uploaded (a run's
// start), 1 both read back (each output of a run; a frame of a picture); range(2) 0 the fragment pass's
// textures, 1 the compute pass's storage buffers
void BM_gpu_wave_transfer(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  static const std::unique_ptr<stepwise::gl::Context> context = stepwise::gl::make_context(stepwise::gpu::backend());
  Grids g(n);
  const auto pass = state.range(2) == 0 ? stepwise::gpu::Pass::fragment : stepwise::gpu::Pass::compute;
  stepwise::gpu::GpuWave gpu(*context, n, stepwise::to_float(g.k), pass);
  const Eigen::VectorXf z_prev = g.z_prev.cast<float>(), z = g.z.cast<float>();
  Eigen::VectorXf back_prev, back;
  gpu.upload(z_prev, z);
  for (auto _ : state) {
    if (state.range(1) == 0) {
      gpu.upload(z_prev, z);
      gpu.finish();
    } else {
      gpu.download(back_prev, back);
      benchmark::DoNotOptimize(back.data());
    }
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * 2 * static_cast<int64_t>(z.size()) * static_cast<int64_t>(sizeof(float)));
  state.SetLabel(pass == stepwise::gpu::Pass::fragment ? "fragment pass's textures" : "compute pass's buffers");
}

// a[i] = b[i] + s c[i] over three arrays of range(0)^2, eight times an iteration
void BM_triad(benchmark::State& state) { stepwise::bench::stream_triad(state, state.range(0) * state.range(0), steps); }

// every grid with one and two threads
void grids(benchmark::internal::Benchmark* b) {
  for (const int threads : {1, 2})
    for (const int n : {256, 1024, 4096}) b->Args({n, threads});
}
BENCHMARK(BM_wave_step)->Apply(grids)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_wave_blocked)->Apply(grids)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_wave_step)->Args({2048, 1})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_gpu_wave)->ArgsProduct({{256, 1024, 2048}, {0, 1, 2, 3}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_gpu_copy)->Arg(1024)->Arg(2048)->Unit(benchmark::kMillisecond)->UseRealTime();
// the device's sizes (scripts/device-check part 4): the passes at 4096^2 and 8192^2, and their copy bound
BENCHMARK(BM_gpu_wave)->ArgsProduct({{4096, 8192}, {0, 1, 3}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_gpu_copy)->Arg(4096)->Arg(8192)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_gpu_wave_transfer)->ArgsProduct({{1024, 2048}, {0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_triad)->Arg(256)->Arg(1024)->Arg(4096)->Unit(benchmark::kMillisecond)->UseRealTime();

// the standing wave (65^2, mu = 0.5, 2 s) by `run`'s path: wave-fd at dt = limit/2, and CVODE at the
// loosest rtol (decades) whose error is no larger
// (made on first use: the model table is another file's static)
const stepwise::Model& standing() {
  static const auto model = stepwise::make_model("standing-wave", {{"size", 65}, {"spacing", 1.0 / 64}, {"mode_m", 1}, {"mode_n", 2}, {"amplitude", 1.0}});
  return *model;
}
double fd_dt() { return stepwise::wave_stable_dt(*standing().as<stepwise::WaveGridView>()) / 2; }

stepwise::StepControl equal_accuracy(const std::string& method) {
  const double target = *stepwise::run_and_measure(standing(), "wave-fd", stepwise::StepControl::fixed(fd_dt()), 2.0, 2.0).error;
  for (double rtol = 1e-3;; rtol /= 10) {
    const auto control = stepwise::StepControl::adaptive(rtol, rtol * 1e-3);
    if (*stepwise::run_and_measure(standing(), method, control, 2.0, 2.0).error <= target || rtol < 1e-12) return control;
  }
}

void BM_standing_wave(benchmark::State& state, const std::string& method) {
  const auto control = method == "wave-fd" ? stepwise::StepControl::fixed(fd_dt()) : equal_accuracy(method);
  double error = 0;
  for (auto _ : state) error = *stepwise::run_and_measure(standing(), method, control, 2.0, 2.0).error;
  state.counters["error"] = error;
  state.counters["rtol"] = control.dt ? 0 : control.rtol;
}
BENCHMARK_CAPTURE(BM_standing_wave, wave_fd, std::string("wave-fd"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_standing_wave, cvode_adams, std::string("cvode-adams"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_standing_wave, cvode_bdf, std::string("cvode-bdf"))->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  using stepwise::bench::RateBound;
  std::vector<RateBound> bounds;
  std::vector<std::pair<std::string, std::string>> pairs{{"BM_standing_wave/cvode_adams", "BM_standing_wave/wave_fd"},
                                                         {"BM_standing_wave/cvode_bdf", "BM_standing_wave/wave_fd"}};
  for (const char* n : {"256", "1024", "4096"}) {
    const std::string triad = fmt::format("BM_triad/{}/real_time", n);
    for (const char* kernel : {"BM_wave_step", "BM_wave_blocked"})
      for (const char* threads : {"1", "2"})
        bounds.push_back({fmt::format("{}/{}/{}/real_time", kernel, n, threads), "cells", triad, "bytes", bytes_per_cell});
    pairs.push_back({fmt::format("BM_wave_step/{}/1/real_time", n), fmt::format("BM_wave_step/{}/2/real_time", n)});
    pairs.push_back({fmt::format("BM_wave_step/{}/1/real_time", n), fmt::format("BM_wave_blocked/{}/1/real_time", n)});
  }
  for (const char* n : {"256", "1024", "2048"})
    pairs.push_back({fmt::format("BM_gpu_wave/{}/real_time", n), fmt::format("BM_wave_step/{}/1/real_time", n)});
  return stepwise::bench::run_with_ratios(argc, argv, pairs, bounds);
}
