// The constrained methods on the chain of N rigid links (scenes/chain.toml): one xpbd iteration is O(N) (a sweep
// over the N constraints), so its time per link and iteration (the counter) stays flat from N = 10 to 1000
// (the target: within 2x); rattle's step (a Newton solve of the N multipliers by LU) against xpbd's frame at the
// same 1 ms step, to 100 links (at 1000 the 1 mm links turn by more than their length in a step and SHAKE's
// Newton iteration does not converge: the run fails, saying so). And the seeds' 32 x 32 flag (scenes/flag.toml) for
// 1 s of 1/60 s frames: xpbd in 20 substeps of one iteration a frame (its springs as compliant constraints), against
// implicit Euler's frame (CHOLMOD) at the same frame step: faster than real time when under 1 s. Ratios printed
// after the table: rattle / xpbd, implicit-euler / xpbd.
#include "models/model.hpp"
#include "ratio_reporter.hpp"
#include "solvers/method_table.hpp"

#include <fmt/format.h>

#include <string>

namespace {

// the model from its initial state to t_end, once a benchmark iteration; a failed run ends the benchmark, saying why
void solve_each_iteration(benchmark::State& state, const stepwise::Model& model, const char* method, const stepwise::StepControl& control, double t_end) {
  const auto integrator = stepwise::make_integrator(method, control);
  const std::vector<double> t_out{t_end};
  for (auto _ : state) {
    const auto r = integrator->solve(model, 0.0, model.initial_state(), t_out);
    if (r.status != stepwise::Status::ok) {
      state.SkipWithError(r.message.c_str());
      break;
    }
    benchmark::DoNotOptimize(r.y_stop[0]);
  }
}

// 100 frames of 1 ms, one substep of `iterations` sweeps (xpbd) or one step (rattle)
void run(benchmark::State& state, const char* method, int links, int iterations) {
  const auto chain = stepwise::make_model("chain", {{"links", links}});
  stepwise::StepControl control = stepwise::StepControl::fixed(1e-3);
  if (std::string_view(method) != "rattle") control.settings["iterations"] = iterations;
  solve_each_iteration(state, *chain, method, control, 0.1);
  // link-iterations a second: frames x iterations x links
  state.counters["link_iterations"] = benchmark::Counter(100.0 * iterations * links, benchmark::Counter::kIsIterationInvariantRate);
}

// one simulated second of the flag in frames of 1/60 s: xpbd in `substeps` substeps of one iteration, or a
// fixed-step method's frame
void flag(benchmark::State& state, const char* method, int substeps) {
  const auto cloth = stepwise::make_model("cloth", {});
  stepwise::StepControl control = stepwise::StepControl::fixed(1.0 / 60);
  if (std::string_view(method) == "xpbd") {
    control.settings["substeps"] = substeps;
    control.settings["iterations"] = 1;
  }
  solve_each_iteration(state, *cloth, method, control, 1.0);
  state.counters["frames"] = benchmark::Counter(60, benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::pair<std::string, std::string>> ratios;
  for (const int links : {10, 100, 1000}) {
    const std::string xpbd = fmt::format("xpbd/links:{}", links), rattle = fmt::format("rattle/links:{}", links);
    benchmark::RegisterBenchmark(xpbd.c_str(), [links](benchmark::State& s) { run(s, "xpbd", links, 10); });
    if (links > 100) continue;  // 1 mm links move more than their length in a 1 ms step: SHAKE does not converge
    benchmark::RegisterBenchmark(rattle.c_str(), [links](benchmark::State& s) { run(s, "rattle", links, 1); });
    ratios.emplace_back(rattle, xpbd);
  }
  benchmark::RegisterBenchmark("flag/xpbd/substeps:20", [](benchmark::State& s) { flag(s, "xpbd", 20); })->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("flag/implicit-euler", [](benchmark::State& s) { flag(s, "implicit-euler", 1); })->Unit(benchmark::kMillisecond);
  ratios.emplace_back("flag/implicit-euler", "flag/xpbd/substeps:20");
  return stepwise::bench::run_with_ratios(argc, argv, ratios);
}
