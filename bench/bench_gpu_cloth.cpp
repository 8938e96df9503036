// The explicit cloth on the GPU: one symplectic Euler step of the seeds' flag (the cloth model's defaults:
// four corners pinned, the gusting wind through its normals, twelve springs a node) at N x N nodes, N = 128, 256,
// 1024, 2048, from the flat start. In one run:
//  - gpu-cloth's fragment pass and gpu-cloth-compute's compute pass on the GL's device (llvmpipe here, its
//    threads LP_NUM_THREADS, by default one per core; a GPU through EGL with STEPWISE_GPU_BACKEND=egl), in
//    float32, finished before the clock stops (4096 a side too, for a device);
//  - the same step on one CPU core, node by node (solvers/cloth_grid.hpp), in float64 (the CPU solver) and
//    in float32 (the shader's reference).
// The model itself stops at 1024 a side (its sparse Jacobians' pattern), so the view is built here from the
// model's defaults, the grid scaled. Ratios: the pass's time over the CPU step's at each size.
//
// And vbd's sweeps (the flag of springs at 32, 64, 128 and 256 a side, a 1/60 s step from its start, 10 sweeps from the
// inertial point): gpu-vbd-compute's pass (the step's upload, the sweeps, the read-back, finished) against vbd's
// sweeps on one CPU core, each after the same host part (the potential's start, not timed), and vbd's sweeps with each
// node read through G's view of it instead of the network's layout. Ratios: pass over CPU, G's view over the layout;
// the layout's rate of node moves at 256 a side against 32's.
#include "models/model.hpp"
#include "solvers/cloth_grid.hpp"
#include "solvers/gpu/gpu_cloth.hpp"
#include "solvers/gpu/gpu_vbd.hpp"
#include "solvers/run_support.hpp"
#include "solvers/vertex_block_descent.hpp"

#include "ratio_reporter.hpp"

#include <fmt/format.h>

#include <map>

namespace {

// the flag's view at n x n: the defaults' physics (from a small model), its nodes' start and pins
const stepwise::ClothGridView& flag_view(int n) {
  static std::map<int, stepwise::ClothGridView> views;
  if (const auto it = views.find(n); it != views.end()) return it->second;
  const auto small = stepwise::make_model("cloth", {{"rows", 4}, {"columns", 4}});
  stepwise::ClothGridView view = *small->as<stepwise::ClothGridView>();
  const double width = view.across * 3, height = view.down * 3, mass = view.node_mass * 16;
  view.rows = view.columns = n;
  view.across = width / (n - 1);
  view.down = height / (n - 1);
  view.node_mass = mass / (static_cast<double>(n) * n);
  view.start.clear();
  view.free_index.assign(static_cast<size_t>(n) * n, 0);
  int free = 0;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      view.start.emplace_back(c * view.across - width / 2, -r * view.down, 0);
      const bool corner = (r == 0 || r == n - 1) && (c == 0 || c == n - 1);
      view.free_index[static_cast<size_t>(r * n + c)] = corner ? -1 : free++;
    }
  return views.emplace(n, std::move(view)).first->second;
}

Eigen::VectorXd flat_start(const stepwise::ClothGridView& view) {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(6 * static_cast<Eigen::Index>(view.start.size() - 4));
  for (size_t k = 0; k < view.start.size(); ++k)
    if (const int i = view.free_index[k]; i >= 0) y.segment<3>(3 * i) = view.start[k];
  return y;
}

constexpr double h = 1e-4;  // below the 2048^2 flag's limit

template <class T>
void BM_cloth_grid_cpu(benchmark::State& state) {
  const auto& view = flag_view(static_cast<int>(state.range(0)));
  auto s = stepwise::cloth_grid::spread<T>(view, flat_start(view)), next = s;
  double t = 0;
  for (auto _ : state) {
    stepwise::cloth_grid::step(stepwise::cloth_grid::constants<T>(view, t, h), view.free_index, s, next);
    std::swap(s, next);
    t += h;
    benchmark::DoNotOptimize(s.x.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(view.start.size()));
}

// the transfers a run adds to the passes, counted apart from them: range(1) 0 the state uploaded (a run's
// start), 1 read back (each output of a run; a frame of a picture); range(2) 0 the fragment pass's textures, 1 the
// compute pass's storage buffers
void BM_gpu_cloth_transfer(benchmark::State& state) {
  static const std::unique_ptr<stepwise::gl::Context> context = stepwise::gl::make_context(stepwise::gpu::backend());
  const auto& view = flag_view(static_cast<int>(state.range(0)));
  stepwise::gpu::GpuCloth gpu(*context, view, state.range(2) == 0 ? stepwise::gpu::Pass::fragment : stepwise::gpu::Pass::compute);
  const auto s = stepwise::cloth_grid::spread<float>(view, flat_start(view));
  auto back = s;
  gpu.upload(s);
  for (auto _ : state) {
    if (state.range(1) == 0) {
      gpu.upload(s);
      gpu.finish();
    } else {
      gpu.download(back);
      benchmark::DoNotOptimize(back.x.data());
    }
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(view.start.size()));
}

// one step as a pass: range(1) 0 the fragment pass (gpu-cloth), 1 the compute pass (gpu-cloth-compute)
void BM_gpu_cloth(benchmark::State& state) {
  static const std::unique_ptr<stepwise::gl::Context> context = stepwise::gl::make_context(stepwise::gpu::backend());
  const auto& view = flag_view(static_cast<int>(state.range(0)));
  const auto pass = state.range(1) == 0 ? stepwise::gpu::Pass::fragment : stepwise::gpu::Pass::compute;
  stepwise::gpu::GpuCloth gpu(*context, view, pass);
  gpu.upload(stepwise::cloth_grid::spread<float>(view, flat_start(view)));
  gpu.set_constants(stepwise::cloth_grid::constants<float>(view, 0, h));
  for (auto _ : state) {
    gpu.step(1);
    gpu.finish();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(view.start.size()));
  state.SetLabel(fmt::format("{}, {}", pass == stepwise::gpu::Pass::fragment ? "fragment" : "compute", context->description()));
}

// 10 sweeps of one 1/60 s step of the n x n flag of springs from its start: range(1) 0 vbd's on one core (from its
// layout of the network: each node's springs and blocks of D0 in sweep order), 1 the pass, 2 vbd's on one core with
// each node read through G's view of it (IncrementalPotential::vertex, the continuum's path). Counters: node_sweep, the
// time a node's move takes (the sweeps' time over nodes x sweeps), and node_sweeps their rate
void BM_vbd_sweeps(benchmark::State& state) {
  static const std::unique_ptr<stepwise::gl::Context> context = stepwise::gl::make_context(stepwise::gpu::backend());
  const int n = static_cast<int>(state.range(0));
  const auto model = stepwise::make_model("cloth", {{"rows", n}, {"columns", n}});
  stepwise::Stats stats;
  const stepwise::CountedSystem system(*model, stats);
  const auto& view = *system.as<stepwise::MassSpringView>();
  const Eigen::VectorXd y = model->initial_state();
  stepwise::IncrementalPotential potential(system, view);
  potential.start(0, y, 1.0 / 60);
  Eigen::SparseMatrix<double> k, d;
  stepwise::force_jacobians(system, view, 0, y, true, k, d);
  const auto colours = stepwise::colour_nodes(k, view.dimension);
  const bool device = state.range(1) == 1;
  std::unique_ptr<stepwise::gpu::GpuVbd> gpu = device ? std::make_unique<stepwise::gpu::GpuVbd>(*context, view, colours, potential.damping()) : nullptr;
  const stepwise::VbdNodes nodes(potential, colours, state.range(1) == 2 ? nullptr : &view);
  Eigen::VectorXd x, decrease;
  for (auto _ : state) {
    x = potential.inertial();
    if (device) {
      gpu->start(potential, x);
      gpu->sweep(10);
      gpu->download(potential, x);
    } else {
      stepwise::vbd_iterate(nodes, x, {.sweeps = 10}, decrease);
    }
    benchmark::DoNotOptimize(x.data());
  }
  const double moves = static_cast<double>(state.iterations()) * view.nodes * 10;
  state.counters["node_sweep"] = benchmark::Counter(moves, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["node_sweeps"] = benchmark::Counter(moves, benchmark::Counter::kIsRate);
  state.SetLabel(device ? fmt::format("gpu-vbd-compute, {}", context->description()) : state.range(1) == 2 ? "vbd, one core, through G's view" : "vbd, one core");
}

#define SIZES ->Arg(128)->Arg(256)->Arg(1024)->Arg(2048)->Unit(benchmark::kMillisecond)->UseRealTime()
BENCHMARK(BM_cloth_grid_cpu<double>) SIZES;
BENCHMARK(BM_cloth_grid_cpu<float>) SIZES;
BENCHMARK(BM_gpu_cloth)->ArgsProduct({{128, 256, 1024, 2048, 4096}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_vbd_sweeps)->ArgsProduct({{32, 64, 128, 256}, {0, 1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_gpu_cloth_transfer)->ArgsProduct({{128, 256, 1024}, {0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::pair<std::string, std::string>> pairs;
  for (const char* n : {"128", "256", "1024", "2048"}) {
    pairs.emplace_back(fmt::format("BM_gpu_cloth/{}/real_time", n), fmt::format("BM_cloth_grid_cpu<double>/{}/real_time", n));
    pairs.emplace_back(fmt::format("BM_cloth_grid_cpu<float>/{}/real_time", n), fmt::format("BM_cloth_grid_cpu<double>/{}/real_time", n));
  }
  for (const char* n : {"32", "64", "128", "256"}) {
    pairs.emplace_back(fmt::format("BM_vbd_sweeps/{}/1/real_time", n), fmt::format("BM_vbd_sweeps/{}/0/real_time", n));
    pairs.emplace_back(fmt::format("BM_vbd_sweeps/{}/2/real_time", n), fmt::format("BM_vbd_sweeps/{}/0/real_time", n));
  }
  // a node's move at 256 a side (the sweep out of the cache) against 32 (in it): the rate's share
  const std::vector<stepwise::bench::RateBound> bounds{{"BM_vbd_sweeps/256/0/real_time", "node_sweeps", "BM_vbd_sweeps/32/0/real_time", "node_sweeps", 1.0}};
  return stepwise::bench::run_with_ratios(argc, argv, pairs, bounds);
}
