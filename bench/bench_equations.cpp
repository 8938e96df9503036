// The pendulum written as equations in a scene file (scenes/pendulum-equations.toml: parsed, differentiated and
// compiled at load time, models/equations.hpp) against the built-in pendulum model, at the same settings, on
// rk4 (dt 1e-3, 10 s), tsitouras54, verner98 and cvode-bdf (rtol 1e-10, atol 1e-13); and the interpreter (no compiler) beside
// both. The target: the compiled equations cost at most 1.2x the built-in model. Ratios printed after the
// table: equations / built-in, interpreted / built-in. On rk4 also the same f hand-written in C++ behind the
// OdeSystem interface (bench/users_pendulum.hpp), as a user's C++ model would be: the built-in pendulum's f is
// inlined into the stepper (solvers/capabilities/inline_rhs.hpp), which no f the compiler cannot see can match.
#include "models/equations.hpp"
#include "ratio_reporter.hpp"
#include "users_pendulum.hpp"
#include "run/scene.hpp"
#include "solvers/method_table.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace {

enum class Which { builtin, compiled, interpreted, cxx_through };

std::unique_ptr<stepwise::Model> pendulum(Which which) {
  if (which == Which::builtin) return stepwise::make_model("pendulum", {{"theta0", 1.0}});
  const auto scene = stepwise::load_scene(std::string(STEPWISE_SOURCE_DIR) + "/scenes/pendulum-equations.toml");
  auto model = stepwise::make_equations(*scene.equations, {}, which == Which::compiled);
  if (which == Which::compiled && !stepwise::equations_evaluation(*model)->compiled)
    throw std::runtime_error("bench_equations: the equations did not compile: " + stepwise::equations_evaluation(*model)->detail);
  return model;
}

void run(benchmark::State& state, const char* method, Which which) {
  const auto model = pendulum(which == Which::cxx_through ? Which::builtin : which);
  const stepwise::bench::UsersPendulum users(9.81);
  const stepwise::OdeSystem& system = which == Which::cxx_through ? static_cast<const stepwise::OdeSystem&>(users) : *model;
  const bool fixed = std::string_view(method) == "rk4";
  const auto control = fixed ? stepwise::StepControl::fixed(1e-3) : stepwise::StepControl::adaptive(1e-10, 1e-13);
  const auto integrator = stepwise::make_integrator(method, control);
  long steps = 0;
  for (auto _ : state) {
    const auto r = integrator->solve(system, 0.0, model->initial_state(), std::vector{10.0});
    steps = r.stats.steps;
    benchmark::DoNotOptimize(r.y_stop[0]);
  }
  state.counters["steps"] = static_cast<double>(steps);
}

}  // namespace

int main(int argc, char** argv) {
  // a cache of the bench's own, so the first run compiles and the timed runs load
  const auto cache = std::filesystem::temp_directory_path() / "stepwise-bench-equations-cache";
  ::setenv("STEPWISE_CACHE", cache.c_str(), 1);
  std::vector<std::pair<std::string, std::string>> ratios;
  for (const char* method : {"rk4", "tsitouras54", "verner98", "cvode-bdf"}) {
    const std::string base = fmt::format("{}/builtin", method);
    benchmark::RegisterBenchmark(base.c_str(), [method](benchmark::State& s) { run(s, method, Which::builtin); });
    benchmark::RegisterBenchmark(fmt::format("{}/equations", method).c_str(), [method](benchmark::State& s) { run(s, method, Which::compiled); });
    benchmark::RegisterBenchmark(fmt::format("{}/interpreted", method).c_str(), [method](benchmark::State& s) { run(s, method, Which::interpreted); });
    if (std::string_view(method) == "rk4") {
      benchmark::RegisterBenchmark("rk4/cxx_through", [](benchmark::State& s) { run(s, "rk4", Which::cxx_through); });
      ratios.emplace_back("rk4/cxx_through", base);
      ratios.emplace_back("rk4/equations", "rk4/cxx_through");
    }
    ratios.emplace_back(fmt::format("{}/equations", method), base);
    ratios.emplace_back(fmt::format("{}/interpreted", method), base);
  }
  const int code = stepwise::bench::run_with_ratios(argc, argv, ratios);
  std::filesystem::remove_all(cache);
  return code;
}
