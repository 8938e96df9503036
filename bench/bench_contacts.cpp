// Rigid bodies in contact, stepped by sequential-impulses: steps per second of the seeds' collapsing wall
// (15 boxes and a ball) and of a resting column of 5 boxes, each against the same run with Gauss-Seidel
// started from zero rather than from the last step's impulses (warm start), measured in the same run, with
// the Gauss-Seidel sweeps each step took on average.
#include "models/model.hpp"
#include "solvers/method_table.hpp"
#include "run/measure.hpp"

#include "ratio_reporter.hpp"

namespace {

using stepwise::Params;

void run_scene(benchmark::State& state, const Params& params, double t_end) {
  const auto model = stepwise::make_model("box-stack", params);
  const auto integrator = stepwise::make_integrator("sequential-impulses", stepwise::StepControl::fixed(1e-3));
  const std::vector<double> t_out{t_end};
  long steps = 0, sweeps = 0;
  for (auto _ : state) {
    const auto result = integrator->integrate(*model, 0, model->initial_state(), t_out);
    if (result.status != stepwise::Status::ok) state.SkipWithError(result.message.c_str());
    steps += result.stats.steps;
    sweeps += result.stats.contact_sweeps;
    benchmark::DoNotOptimize(result.y_stop.data());
  }
  state.counters["steps"] = benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
  state.counters["sweeps/step"] = static_cast<double>(sweeps) / static_cast<double>(steps);
}

// the default wall hit by the ball: 1 s, the collapse's first second
void BM_stack_collapse(benchmark::State& state) { run_scene(state, {}, 1.0); }
void BM_stack_collapse_cold(benchmark::State& state) { run_scene(state, {{"warm_start", 0}}, 1.0); }
// one column of 5 boxes, the ball thrown from too far to arrive: resting contact only
const Params column{{"columns", 1}, {"projectile_distance", 1000}};
void BM_column_resting(benchmark::State& state) { run_scene(state, column, 0.5); }
void BM_column_resting_cold(benchmark::State& state) {
  Params cold = column;
  cold["warm_start"] = 0;
  run_scene(state, cold, 0.5);
}
BENCHMARK(BM_stack_collapse)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_stack_collapse_cold)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_column_resting)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_column_resting_cold)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  return stepwise::bench::run_with_ratios(argc, argv,
                                          {{"BM_stack_collapse_cold", "BM_stack_collapse"}, {"BM_column_resting_cold", "BM_column_resting"}});
}
