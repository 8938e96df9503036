// Google Benchmark main that prints, after the usual table, the ratio of each benchmark's time to its
// peer's measured in the same run (the time it is timed by: wall-clock where it uses real time, as its
// threads' or a GPU's work is not the calling thread's CPU time, else CPU time): "ratio A / B = x", and the fraction of a bound a rate reaches: "A reaches
// x of the bound from B". With --benchmark_repetitions the medians are compared.
#pragma once

#include <benchmark/benchmark.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace stepwise::bench {

// a rate counter of one benchmark against the bound another one's rate sets: items per second at most
// (bound's rate) / cost, e.g. particle-steps/s against triad bytes/s over the bytes a particle-step moves
struct RateBound {
  std::string name, counter;              // the measured rate
  std::string bound_name, bound_counter;  // the rate that bounds it
  double cost;                            // bound units per measured item
};

class RatioReporter : public benchmark::ConsoleReporter {
 public:
  RatioReporter(std::vector<std::pair<std::string, std::string>> pairs, std::vector<RateBound> bounds)
      : pairs_(std::move(pairs)), bounds_(std::move(bounds)) {}
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& run : runs) {
      const std::string name = run.run_name.str();
      const bool median = run.run_type == Run::RT_Aggregate && run.aggregate_name == "median";
      if ((run.run_type == Run::RT_Iteration && !median_.contains(name)) || median) {
        if (median) median_[name] = true;
        time_[name] = run.run_name.time_type == "real_time" ? run.GetAdjustedRealTime() : run.GetAdjustedCPUTime();
        for (const auto& [key, counter] : run.counters) counters_[name][key] = counter.value;
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    for (const auto& [a, b] : pairs_)
      if (time_.contains(a) && time_.contains(b)) std::printf("ratio %s / %s = %.3f\n", a.c_str(), b.c_str(), time_[a] / time_[b]);
    for (const auto& b : bounds_) {
      if (!counters_[b.name].contains(b.counter) || !counters_[b.bound_name].contains(b.bound_counter)) continue;
      const double rate = counters_[b.name][b.counter], bound = counters_[b.bound_name][b.bound_counter] / b.cost;
      std::printf("bound %s: %.4g %s/s, bound %.4g from %s: %.3f of it\n", b.name.c_str(), rate, b.counter.c_str(), bound,
                  b.bound_name.c_str(), rate / bound);
    }
  }

 private:
  std::vector<std::pair<std::string, std::string>> pairs_;
  std::vector<RateBound> bounds_;
  std::map<std::string, double> time_;
  std::map<std::string, std::map<std::string, double>> counters_;
  std::map<std::string, bool> median_;  // names whose median has been seen
};

// run every registered benchmark and print the ratios of the given pairs (names as Google Benchmark prints
// them) and the fractions of the given bounds
inline int run_with_ratios(int argc, char** argv, std::vector<std::pair<std::string, std::string>> pairs,
                           std::vector<RateBound> bounds = {}) {
  benchmark::Initialize(&argc, argv);
  RatioReporter reporter(std::move(pairs), std::move(bounds));
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}

}  // namespace stepwise::bench
