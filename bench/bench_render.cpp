// A 1280 x 720 frame of the water scene (water-drop, 64 x 64, caustics on a 512^2 photon map), split into
// its phases: simulating one frame's worth of steps (1/30 s), the caustics pass, the drawing (caustics and
// shading), the read-back, the whole draw, and PNG encoding; against an empty frame (clear and read back) measured in the same
// run, the floor any frame pays. The target: the draw without encoding under 50 ms on two cores.
#include "ratio_reporter.hpp"

#include "models/model.hpp"
#include "render/caustics.hpp"
#include "render/renderer.hpp"
#include "run/measure.hpp"
#include "solvers/gpu/gpu_grid.hpp"

#include <benchmark/benchmark.h>


namespace {

using namespace stepwise;

constexpr int width = 1280, height = 720;

// OSMesa (llvmpipe), or a GPU through EGL with STEPWISE_GPU_BACKEND=egl, as the GPU methods' benchmarks
gl::Context& context() {
  static const std::unique_ptr<gl::Context> c = gl::make_context(gpu::backend());
  return *c;
}

struct WaterScene {
  std::unique_ptr<Model> model = make_model("water-drop", {});
  Eigen::VectorXd y;
  Shapes shapes;
  render::View view;
  WaterScene() {
    // a moment after the drop: waves across the pool
    Measured m = run_and_measure(*model, "wave-fd", StepControl::fixed(5e-3), 0.5, 0.5);
    y = m.result.y_stop;
    shapes = *model->shapes(y);
    view = render::make_view({&shapes, 1}, {}, width, height);
  }
};

const WaterScene& scene() {
  static const WaterScene s;
  return s;
}

void BM_simulate_frame(benchmark::State& state) {
  const auto& s = scene();
  for (auto _ : state) benchmark::DoNotOptimize(run_and_measure(*s.model, "wave-fd", StepControl::fixed(5e-3), 1.0 / 30, 1.0 / 30));
}

void BM_caustics_pass(benchmark::State& state) {
  const auto& s = scene();
  render::PhotonMap map(context(), s.view.photon_resolution);
  for (auto _ : state) {
    map.build(*s.shapes.water, s.view.light, s.view.pool_depth);
    context().gl().Finish();
  }
}

void BM_water_frame(benchmark::State& state) {
  const auto& s = scene();
  render::Renderer renderer(context(), width, height);
  for (auto _ : state) benchmark::DoNotOptimize(renderer.draw(s.shapes, {}, s.view));
}

// the water frame's two halves: the drawing (caustics and shading, waited for), and the read-back alone
void BM_water_shading(benchmark::State& state) {
  const auto& s = scene();
  render::Renderer renderer(context(), width, height);
  for (auto _ : state) {
    renderer.render(s.shapes, {}, s.view);
    context().gl().Finish();
  }
}

void BM_read_back(benchmark::State& state) {
  const auto& s = scene();
  render::Renderer renderer(context(), width, height);
  renderer.render(s.shapes, {}, s.view);
  context().gl().Finish();
  for (auto _ : state) benchmark::DoNotOptimize(renderer.read());
}

void BM_empty_frame(benchmark::State& state) {
  const auto& s = scene();
  render::Renderer renderer(context(), width, height);
  const Shapes nothing;
  for (auto _ : state) benchmark::DoNotOptimize(renderer.draw(nothing, {}, s.view));
}

void BM_encode_png(benchmark::State& state) {
  const auto& s = scene();
  render::Renderer renderer(context(), width, height);
  const render::Image image = renderer.draw(s.shapes, {}, s.view);
  for (auto _ : state) benchmark::DoNotOptimize(render::encode_png(image));
}

BENCHMARK(BM_simulate_frame)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_caustics_pass)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_water_frame)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_water_shading)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_read_back)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_empty_frame)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_encode_png)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::pair<std::string, std::string>> pairs{{"BM_water_frame/real_time", "BM_empty_frame/real_time"},
                                                               {"BM_caustics_pass/real_time", "BM_water_frame/real_time"},
                                                               {"BM_water_shading/real_time", "BM_water_frame/real_time"},
                                                               {"BM_read_back/real_time", "BM_water_frame/real_time"},
                                                               {"BM_encode_png/real_time", "BM_water_frame/real_time"}};
  return stepwise::bench::run_with_ratios(argc, argv, pairs, {});
}
