// The constrained methods on the chain of N rigid links (scenes/chain.toml): one xpbd iteration is O(N) (a sweep
// over the N constraints), so its time per link and iteration stays flat from N = 10 to 1000 (issue 50: within
// 2x); rattle's step (a Newton solve of the N multipliers by LU) against xpbd's at the same frame step. Ratios
// printed after the table: each N against N = 10 per link-iteration, and rattle / xpbd per step.
#include "models/model.hpp"
#include "ratio_reporter.hpp"
#include "solvers/method_table.hpp"

#include <fmt/format.h>

#include <string>

namespace {

// 100 frames of 1 ms, one substep of `iterations` sweeps (xpbd) or one step (rattle)
void run(benchmark::State& state, const char* method, int links, int iterations) {
  const auto chain = stepwise::make_model("chain", {{"links", links}});
  stepwise::StepControl control = stepwise::StepControl::fixed(1e-3);
  control.iterations = iterations;
  const auto integrator = stepwise::make_integrator(method, control);
  const std::vector<double> t_out{0.1};
  for (auto _ : state) {
    const auto r = integrator->solve(*chain, 0.0, chain->initial_state(), t_out);
    benchmark::DoNotOptimize(r.y_stop[0]);
  }
  // link-iterations a second: frames x iterations x links
  state.counters["link_iterations"] = benchmark::Counter(100.0 * iterations * links, benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::pair<std::string, std::string>> ratios;
  for (const int links : {10, 100, 1000}) {
    const std::string xpbd = fmt::format("xpbd/links:{}", links), rattle = fmt::format("rattle/links:{}", links);
    benchmark::RegisterBenchmark(xpbd.c_str(), [links](benchmark::State& s) { run(s, "xpbd", links, 10); });
    benchmark::RegisterBenchmark(rattle.c_str(), [links](benchmark::State& s) { run(s, "rattle", links, 1); });
    ratios.emplace_back(rattle, xpbd);
  }
  return stepwise::bench::run_with_ratios(argc, argv, ratios);
}
