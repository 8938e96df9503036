// The stiff target: on Van der Pol at mu = 1000 to t = 2 (scenes/van-der-pol-stiff.toml, its error against
// a converged reference: verification/reference.hpp), the CPU time each stiff method needs to reach an error of
// 1e-4 ... 1e-8, each method swept over rtol in thirds of a decade (atol 1e-3 rtol), one output at t_end. Printed
// after the table, per error: the cheapest time of rodas4 and rodas5 over the best of cvode-bdf, gsl-bsimp and
// the ARKODE DIRK methods (target: at most 1.0), and the best explicit method's over it too (the system is stiff
// by its spectrum, yet small: an explicit step costs little).
#include "models/equations.hpp"
#include "ratio_reporter.hpp"
#include "run/measure.hpp"
#include "run/scene.hpp"
#include "verification/reference.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>

namespace {

const char* const methods[] = {"rodas4", "rodas5", "cvode-bdf", "gsl-bsimp", "arkode-dirk-sdirk21", "arkode-dirk-trbdf2", "arkode-dirk-kvaerno32",
                               "arkode-dirk-kvaerno43", "arkode-dirk-kvaerno54", "tsitouras54", "verner98", "gsl-rk8pd"};
const char* const peers[] = {"cvode-bdf", "gsl-bsimp", "arkode-dirk-sdirk21", "arkode-dirk-trbdf2", "arkode-dirk-kvaerno32", "arkode-dirk-kvaerno43",
                             "arkode-dirk-kvaerno54"};
const char* const explicit_methods[] = {"tsitouras54", "verner98", "gsl-rk8pd"};

std::unique_ptr<stepwise::Model> vdp() {
  const auto scene = stepwise::load_scene(std::string(STEPWISE_SOURCE_DIR) + "/scenes/van-der-pol-stiff.toml");
  return stepwise::make_equations(*scene.equations, {});
}

struct Point {
  std::string method;
  double rtol, error;
};
std::map<std::string, Point> points;  // by benchmark name

// CPU time per run, and the error as a counter. Timed by the run's own thread CPU time (RunResult's stats, as the
// report times its points): a process's CPU time would count the spinning of idle BLAS and OpenMP worker threads
// left by the reference's solvers (perf: a third of the samples in sched_yield)
void run(benchmark::State& state, const char* method, double rtol, const Eigen::VectorXd* reference) {
  const auto model = vdp();
  const auto integrator = stepwise::make_integrator(method, stepwise::StepControl::adaptive(rtol, 1e-3 * rtol));
  const std::vector<double> t_out{2.0};
  double error = NAN;
  for (auto _ : state) {
    const auto r = integrator->integrate(*model, 0.0, model->initial_state(), t_out);
    error = r.status == stepwise::Status::ok ? stepwise::max_norm_error(r.y_stop, *reference) : NAN;
    benchmark::DoNotOptimize(r.y_stop[0]);
    state.SetIterationTime(r.stats.cpu_seconds);
  }
  state.counters["error"] = error;
}

class StiffReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& r : runs)
      if (r.run_type == Run::RT_Iteration) {
        const std::string name = r.run_name.str().substr(0, r.run_name.str().find("/min_time"));  // as registered
        cpu_[name] = r.GetAdjustedRealTime();  // the manual time: thread CPU seconds
        error_[name] = r.counters.at("error").value;
      }
    ConsoleReporter::ReportRuns(runs);
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    const auto cheapest = [&](const std::string& method, double target) {
      double best = INFINITY;
      for (const auto& [name, p] : points)
        if (p.method == method && error_.count(name) && error_[name] <= target) best = std::min(best, cpu_[name]);
      return best;
    };
    for (const double target : {1e-4, 1e-5, 1e-6, 1e-7, 1e-8}) {
      double peer = INFINITY, explicit_best = INFINITY;
      std::string peer_name, explicit_name;
      for (const char* m : peers)
        if (const double c = cheapest(m, target); c < peer) peer = c, peer_name = m;
      for (const char* m : explicit_methods)
        if (const double c = cheapest(m, target); c < explicit_best) explicit_best = c, explicit_name = m;
      for (const char* m : {"rodas4", "rodas5"})
        std::printf("ratio %s / best stiff peer (%s) at error %.0e = %.3f\n", m, peer_name.c_str(), target, cheapest(m, target) / peer);
      std::printf("ratio best explicit (%s) / best stiff peer (%s) at error %.0e = %.3f\n", explicit_name.c_str(), peer_name.c_str(), target,
                  explicit_best / peer);
    }
  }

 private:
  std::map<std::string, double> cpu_, error_;
};

}  // namespace

int main(int argc, char** argv) {
  const auto cache = std::filesystem::temp_directory_path() / "stepwise-bench-stiff-cache";
  ::setenv("STEPWISE_CACHE", cache.c_str(), 1);
  static const Eigen::VectorXd reference = stepwise::converged_reference(*vdp(), 2.0).y;
  for (const char* method : methods)
    for (int k = 0; k <= 24; ++k) {
      // rtol from 1e-2 to 1e-10 in thirds of a decade
      const double rtol = std::stod(fmt::format("{:.3g}", std::pow(10.0, -2.0 - k / 3.0)));
      const std::string name = fmt::format("{}/rtol:{:.3g}", method, rtol);
      points[name] = {method, rtol, NAN};
      benchmark::RegisterBenchmark(name.c_str(), [method, rtol](benchmark::State& s) { run(s, method, rtol, &reference); })->MinTime(0.01)->UseManualTime();
    }
  benchmark::Initialize(&argc, argv);
  StiffReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  std::filesystem::remove_all(cache);
  return 0;
}
