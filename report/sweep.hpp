// A study's sweep: independent points run on a pool of threads, results kept in point order, progress shown.
#pragma once

#include <chrono>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

namespace stepwise {

// progress of the running study: a bar redrawn in place on a terminal, plain lines otherwise
class Progress {
 public:
  Progress();
  void begin_study(std::string_view name);
  // a sweep of points whose expected costs add up to `weight` (the point count where they are not known)
  void begin_sweep(size_t points, double weight);
  void point_done(const std::string& label, double weight);  // thread-safe
  void end_study(double seconds);

 private:
  void draw(const std::string& label);
  bool terminal_;
  std::mutex mutex_;
  std::string study_;
  size_t total_ = 0, done_ = 0, last_line_ = 0;  // last_line_: points done at the last plain line
  double total_weight_ = 0, done_weight_ = 0;     // the points' expected costs: the time left is the elapsed
                                                  // time scaled by the cost left over the cost done
  std::chrono::steady_clock::time_point sweep_start_;
};

// what a study runs with: the sweep size and the pool its points share
struct StudyContext {
  bool quick = false;
  int threads = 1;
  Progress* progress = nullptr;

  // task(i) for each i < labels.size(), on up to `threads` threads; results in index order, whatever the
  // thread count (a point never reads another's result). An exception from any point is rethrown here.
  // `costs`, where given, are the points' expected costs (any unit): the costliest run first (so that no
  // thread is left with one long point at the end) and the time left is estimated from them
  template <class R>
  std::vector<R> sweep(const std::vector<std::string>& labels, const std::function<R(size_t)>& task, const std::vector<double>& costs = {}) const {
    std::vector<R> results(labels.size());
    run_points(labels, [&](size_t i) { results[i] = task(i); }, costs);
    return results;
  }

 private:
  void run_points(const std::vector<std::string>& labels, const std::function<void(size_t)>& point, const std::vector<double>& costs) const;
};

}  // namespace stepwise
