// The constrained methods on the chain of N rigid links (scenes/chain.toml): one xpbd iteration is O(N) (a sweep
// over the N constraints), so its time per link and iteration (the counter) stays flat from N = 10 to 1000
// (issue 50: within 2x); rattle's step (a Newton solve of the N multipliers by LU) against xpbd's frame at the
// same 1 ms step, to 100 links (at 1000 the 1 mm links turn by more than their length in a step and SHAKE's
// Newton iteration does not converge: the run fails, saying so). Ratios printed after the table: rattle / xpbd.
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
    if (r.status != stepwise::Status::ok) {
      state.SkipWithError(r.message.c_str());
      break;
    }
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
    if (links > 100) continue;  // 1 mm links move more than their length in a 1 ms step: SHAKE does not converge
    benchmark::RegisterBenchmark(rattle.c_str(), [links](benchmark::State& s) { run(s, "rattle", links, 1); });
    ratios.emplace_back(rattle, xpbd);
  }
  return stepwise::bench::run_with_ratios(argc, argv, ratios);
}
