// A study's sweep: independent points run on a pool of threads, results kept in point order, progress shown;
// under mpirun the points are shared among the ranks too, by expected cost, and every rank gets every result.
#pragma once

#include <stepwise/report/pack.hpp>

#include <chrono>
#include <cstddef>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace stepwise {

// progress of the running study: a bar redrawn in place on a terminal, plain lines otherwise
class Progress {
 public:
  Progress();
  void begin_study(std::string_view name);
  // a sweep of points with their expected costs (CPU nanoseconds where given, else 1 each) and groups (points
  // of one group, one method on one scene, cost alike relative to their expectation), run on `threads` threads
  void begin_sweep(const std::vector<double>& costs, const std::vector<std::string>& groups, int threads, bool in_nanoseconds);
  void point_started(size_t point);                                         // thread-safe
  void point_done(size_t point, const std::string& label, double seconds);  // thread-safe
  void end_study(double seconds);
  // this machine's slowness against the cost model's (report/cost_model.hpp machine_slowness): the seconds a
  // unit of expected cost takes in a group with no point done scale by it
  void set_slowness(double slowness) { slowness_ = slowness; }
  double slowness() const { return slowness_; }

 private:
  void draw(const std::string& label);
  bool terminal_;
  std::mutex mutex_;
  std::string study_;
  // the time left: the expected cost left in each group, times the seconds its done points took per unit of
  // expected cost (the whole sweep's where the group has none done yet), less what the points in hand have
  // run so far (up to their own expectation), over the threads
  double seconds_left() const;
  std::map<size_t, std::chrono::steady_clock::time_point> running_;  // the points in hand (index in costs_), since when
  size_t total_ = 0, done_ = 0, sweep_offset_ = 0;  // sweep_offset_: the running sweep's first point in costs_
  int threads_ = 1;
  bool costs_given_ = false;  // the running sweep's costs are expected nanoseconds
  double slowness_ = 1;
  std::vector<double> costs_;
  std::vector<size_t> group_of_;  // each point's group
  struct Group {
    double expected_left = 0, expected_done = 0, seconds_done = 0;
  };
  std::vector<Group> groups_;
  double total_weight_ = 0, done_weight_ = 0, last_line_weight_ = 0;  // last_line_weight_: cost done at the last plain line
  std::chrono::steady_clock::time_point last_line_time_;
};

// how the sweeps' points were shared among the ranks: each rank's busy seconds (its points' wall time until it
// handed them over), summed over the sweeps
struct RankLoad {
  std::vector<double> seconds;
};

// a point that failed, on whichever rank: the same on every rank, so every rank stops the same way
struct SweepError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct StudyScene;

// what a study runs with: the sweep size and the pool its points share
struct StudyContext {
  bool quick = false;
  int threads = 1;
  Progress* progress = nullptr;
  // share the points among the MPI ranks (every rank runs the same sweeps in the same order): off for a sweep
  // only rank 0 runs (the pictures, drawn where they are written)
  bool distribute = true;
  RankLoad* load = nullptr;
  // `stepwise study NAME --scene FILE`: the user's scene, in place of the study's own (report/studies/study_scenes.hpp)
  const std::vector<StudyScene>* scenes = nullptr;
  // where the study's outputs go, and the scenes a drawn study draws (report/studies.hpp's Study::drawn: it writes
  // its pictures and videos there itself)
  std::filesystem::path out, scenes_dir;

  // task(i) for each i < labels.size(), on up to `threads` threads; results in index order, whatever the
  // thread count (a point never reads another's result). An exception from any point is rethrown here.
  // `costs`, where given, are the points' expected CPU times (report/cost_model.hpp): the costliest run first
  // (so that no thread is left with one long point at the end) and the time left is estimated from them. In
  // nanoseconds; or in any one unit for a sweep without groups, whose scale is learned from its points done (a
  // group none of whose points is done yet is taken at the nanosecond scale).
  // `groups` name which points cost alike relative to their expected costs (the time-left estimate learns
  // each group's ratio from its points done).
  // Under mpirun each rank runs a share of the points, chosen by cost (the costliest point to the rank with
  // the least cost so far), and every rank gets every result (R is packed: report/pack.hpp); a point's
  // exception becomes a SweepError naming its rank and label, on every rank.
  template <class R>
  std::vector<R> sweep(const std::vector<std::string>& labels, const std::function<R(size_t)>& task, const std::vector<double>& costs = {},
                       const std::vector<std::string>& groups = {}) const {
    std::vector<R> results(labels.size());
    run_points(labels, [&](size_t i) { results[i] = task(i); }, costs, groups, [&](size_t i, pack::Writer& w) { pack::put(w, results[i]); },
               [&](size_t i, pack::Reader& r) { pack::get(r, results[i]); });
    return results;
  }

 private:
  void run_points(const std::vector<std::string>& labels, const std::function<void(size_t)>& point, const std::vector<double>& costs,
                  const std::vector<std::string>& groups, const std::function<void(size_t, pack::Writer&)>& put,
                  const std::function<void(size_t, pack::Reader&)>& get) const;
};

// the points each of `ranks` ranks runs, in the order it runs them (the costliest first): each point in turn,
// costliest first, to the rank whose share costs least so far (lowest rank on a tie); the same on every rank
std::vector<std::vector<size_t>> share_by_cost(const std::vector<double>& costs, int ranks);

}  // namespace stepwise
