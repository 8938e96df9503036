// Google Benchmark main that prints, after the usual table, the ratio of each benchmark's CPU time to its
// peer's measured in the same run: "ratio A / B = x". With --benchmark_repetitions the medians are compared.
#pragma once

#include <benchmark/benchmark.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace stepwise::bench {

class RatioReporter : public benchmark::ConsoleReporter {
 public:
  explicit RatioReporter(std::vector<std::pair<std::string, std::string>> pairs) : pairs_(std::move(pairs)) {}
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& run : runs) {
      if (run.run_type == Run::RT_Iteration && !median_.contains(run.run_name.str())) cpu_[run.run_name.str()] = run.GetAdjustedCPUTime();
      if (run.run_type == Run::RT_Aggregate && run.aggregate_name == "median") {
        median_[run.run_name.str()] = true;
        cpu_[run.run_name.str()] = run.GetAdjustedCPUTime();
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    for (const auto& [a, b] : pairs_)
      if (cpu_.contains(a) && cpu_.contains(b)) std::printf("ratio %s / %s = %.3f\n", a.c_str(), b.c_str(), cpu_[a] / cpu_[b]);
  }

 private:
  std::vector<std::pair<std::string, std::string>> pairs_;
  std::map<std::string, double> cpu_;
  std::map<std::string, bool> median_;  // names whose median has been seen
};

// run every registered benchmark and print the ratios of the given pairs (names as Google Benchmark prints them)
inline int run_with_ratios(int argc, char** argv, std::vector<std::pair<std::string, std::string>> pairs) {
  benchmark::Initialize(&argc, argv);
  RatioReporter reporter(std::move(pairs));
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}

}  // namespace stepwise::bench
