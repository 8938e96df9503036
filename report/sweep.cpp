#include "sweep.hpp"

#include "run/interrupt.hpp"
#include "run/ranks.hpp"

#include <fmt/format.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <optional>
#include <cstdio>
#include <thread>

namespace stepwise {

Progress::Progress() : terminal_(isatty(STDERR_FILENO) != 0) {}

void Progress::begin_study(std::string_view name) {
  std::lock_guard lock(mutex_);
  study_ = name;
  total_ = done_ = sweep_offset_ = 0;
  total_weight_ = done_weight_ = last_line_weight_ = 0;
  costs_.clear();
  group_of_.clear();
  groups_.clear();
  if (!terminal_) fmt::print(stderr, "stepwise: study {} ...\n", study_);
}

void Progress::begin_sweep(const std::vector<double>& costs, const std::vector<std::string>& groups, int threads, bool in_nanoseconds) {
  std::lock_guard lock(mutex_);
  costs_given_ = in_nanoseconds;
  if (done_ == 0) last_line_time_ = std::chrono::steady_clock::now();
  threads_ = std::max(1, threads);
  sweep_offset_ = costs_.size();
  // a study may run several sweeps, one after another: each sweep's groups are its own
  std::map<std::string, size_t> index;
  for (size_t i = 0; i < costs.size(); ++i) {
    const auto [it, added] = index.try_emplace(groups.empty() ? std::string() : groups[i], groups_.size());
    if (added) groups_.emplace_back();
    group_of_.push_back(it->second);
    costs_.push_back(costs[i]);
    groups_[it->second].expected_left += costs[i];
    total_weight_ += costs[i];
  }
  total_ += costs.size();
}

void Progress::point_started(size_t point) {
  std::lock_guard lock(mutex_);
  running_[sweep_offset_ + point] = std::chrono::steady_clock::now();
}

void Progress::point_done(size_t point, const std::string& label, double seconds) {
  std::lock_guard lock(mutex_);
  const size_t i = sweep_offset_ + point;
  running_.erase(i);
  Group& g = groups_[group_of_[i]];
  g.expected_left -= costs_[i];
  g.expected_done += costs_[i];
  g.seconds_done += seconds;
  done_weight_ += costs_[i];
  ++done_;
  draw(label);
}

double Progress::seconds_left() const {
  // a group none of whose points is done yet: its expected cost as the sweep gave it, in nanoseconds where the
  // sweep gave costs (they are: work-precision's and cloth-realtime's models), else the whole sweep's ratio so far
  double expected = 0, seconds = 0;
  for (const Group& g : groups_) expected += g.expected_done, seconds += g.seconds_done;
  // (the cost models overestimate by a steady factor, 0.4 of their unit taken as 1 ns, and a machine's own speed
  // scales every point alike: hence the slowness measured at the start)
  const double prior = costs_given_ ? 0.4e-9 * slowness_ : expected > 0 ? seconds / expected : 0;
  const auto ratio = [&](const Group& g) { return g.expected_done > 0 ? g.seconds_done / g.expected_done : prior; };
  double left = 0;
  for (const Group& g : groups_) left += std::max(0.0, g.expected_left) * ratio(g);
  // the points in hand are part done: a point that has run longer than expected is taken as about to finish
  const auto now = std::chrono::steady_clock::now();
  for (const auto& [i, since] : running_)
    left -= std::min(std::chrono::duration<double>(now - since).count(), costs_[i] * ratio(groups_[group_of_[i]]));
  return std::max(0.0, left) / threads_;
}

namespace {
// a time left as the line says it: to a tenth of a second under 10 s, where whole seconds are too coarse to be
// within a factor of two ("~1 s" says anything from 0.5 to 1.5), else whole seconds
std::string seconds_shown(double seconds) { return seconds < 9.95 ? fmt::format("{:.1f}", seconds) : fmt::format("{:.0f}", seconds); }
}  // namespace

void Progress::draw(const std::string& label) {
  if (total_ == 0) return;
  const double left = seconds_left();
  if (terminal_) {
    constexpr int width = 24;
    const int filled = static_cast<int>(width * done_ / total_);
    std::string shown = label.size() > 40 ? label.substr(0, 39) + "~" : label;
    fmt::print(stderr, "\r\033[K{} [{}{}] {}/{} {} ~{} s left in this sweep", study_, std::string(filled, '#'), std::string(width - filled, '.'),
               done_, total_, shown, seconds_shown(left));
  } else if (const auto now = std::chrono::steady_clock::now();
             done_ == total_ || (done_weight_ - last_line_weight_) * 10 >= total_weight_ || now - last_line_time_ >= std::chrono::seconds(30)) {
    // a line each tenth of the sweep's expected cost (the costliest points come first, so a tenth of the
    // count could be most of the time), and at least every 30 s: a log keeps the progress without a line per point
    last_line_weight_ = done_weight_;
    last_line_time_ = now;
    fmt::print(stderr, "stepwise:   {}/{} points, last {}, ~{} s left in this sweep\n", done_, total_, label, seconds_shown(left));
  }
}

void Progress::end_study(double seconds) {
  std::lock_guard lock(mutex_);
  if (terminal_) fmt::print(stderr, "\r\033[Kstepwise: study {} {:.1f} s\n", study_, seconds);
  else fmt::print(stderr, "stepwise: study {} done in {:.1f} s\n", study_, seconds);
}

std::vector<std::vector<size_t>> share_by_cost(const std::vector<double>& costs, int ranks) {
  std::vector<size_t> order(costs.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return costs[a] > costs[b]; });
  std::vector<std::vector<size_t>> shares(static_cast<size_t>(std::max(ranks, 1)));
  std::vector<double> load(shares.size(), 0.0);
  for (const size_t i : order) {
    const size_t r = static_cast<size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    shares[r].push_back(i);
    load[r] += costs[i];
  }
  return shares;
}

namespace {

std::string message_of(const std::exception_ptr& e) {
  try {
    std::rethrow_exception(e);
  } catch (const std::exception& x) {
    return std::string(x.what());
  } catch (...) {
    return std::string("an unknown exception");
  }
}

std::vector<size_t> indices(size_t n) {
  std::vector<size_t> all(n);
  for (size_t i = 0; i < n; ++i) all[i] = i;
  return all;
}

// One call of run_points: its points run on this rank's threads, and under mpirun shared among the ranks, each
// rank's results handed to every rank
class PointSweep {
 public:
  PointSweep(const StudyContext& ctx, const std::vector<std::string>& labels, const std::function<void(size_t)>& point,
             const std::vector<double>& costs, const std::vector<std::string>& groups,
             const std::function<void(size_t, pack::Writer&)>& put, const std::function<void(size_t, pack::Reader&)>& get)
      : ctx_(ctx), labels_(labels), point_(point), costs_(costs), groups_(groups), put_(put), get_(get),
        weights_(costs.empty() ? std::vector<double>(labels.size(), 1.0) : costs),
        ranks_(ctx.distribute ? ranks::size() : 1), me_(ctx.distribute ? ranks::rank() : 0),
        errors_(labels.size()), took_(labels.size(), 0.0) {}

  void run() {
    if (ranks_ == 1) {
      add_load({run_here(share_by_cost(weights_, 1)[0])});  // every point, the costliest first
      for (const auto& e : errors_)
        if (e) std::rethrow_exception(e);
      return;
    }
    std::vector<size_t> rest = indices(labels_.size());
    std::vector<double> cost_of(weights_);
    if (!costs_.empty() && !groups_.empty()) calibrate(rest, cost_of);
    std::vector<double> rest_costs;
    for (const size_t i : rest) rest_costs.push_back(cost_of[i]);
    round(rest, rest_costs);
    if (!failed_.empty()) throw SweepError(failed_.begin()->second);
  }

 private:
  // these points (the costliest first) on this rank's threads; the seconds until the last is done
  double run_here(const std::vector<size_t>& mine) {
    const size_t n = std::min(mine.size(), static_cast<size_t>(std::max(ctx_.threads, 1)));
    if (ctx_.progress) {
      std::vector<double> my_weights;
      std::vector<std::string> my_groups;
      for (const size_t i : mine) {
        my_weights.push_back(weights_[i]);
        if (!groups_.empty()) my_groups.push_back(groups_[i]);
      }
      ctx_.progress->begin_sweep(my_weights, my_groups, static_cast<int>(std::max<size_t>(n, 1)), !costs_.empty());
    }
    const auto start = std::chrono::steady_clock::now();
    std::atomic<size_t> next{0};
    auto worker = [&] {
      for (size_t k = next++; k < mine.size(); k = next++) run_one(k, mine[k]);
    };
    std::vector<std::jthread> pool;
    for (size_t k = 1; k < n; ++k) pool.emplace_back(worker);
    worker();
    pool.clear();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  // point i, the k-th of this rank's share: its error kept, its seconds measured
  void run_one(size_t k, size_t i) {
    const auto begun = std::chrono::steady_clock::now();
    if (ctx_.progress) ctx_.progress->point_started(k);
    try {
      point_(i);
    } catch (...) {
      errors_[i] = std::current_exception();
    }
    took_[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - begun).count();
    if (ctx_.progress) ctx_.progress->point_done(k, labels_[i], took_[i]);
  }

  void add_load(const std::vector<double>& seconds) {
    if (!ctx_.load) return;
    ctx_.load->seconds.resize(std::max(ctx_.load->seconds.size(), seconds.size()));
    for (size_t r = 0; r < seconds.size(); ++r) ctx_.load->seconds[r] += seconds[r];
  }

  // Under mpirun: hand this rank's results to every rank (its busy time, then for each point its index, its
  // seconds, whether it failed, and the error's message or the result) and take theirs
  void hand_over(const std::vector<size_t>& mine, double busy) {
    pack::Writer w;
    pack::put(w, busy);
    for (const size_t i : mine) {
      pack::put(w, i);
      pack::put(w, took_[i]);
      pack::put(w, errors_[i] != nullptr);
      if (errors_[i]) pack::put(w, message_of(errors_[i]));
      else put_(i, w);
    }
    const std::vector<std::string> bytes = ranks::all_gather(w.bytes());
    std::vector<double> seconds(static_cast<size_t>(ranks_));
    for (int r = 0; r < ranks_; ++r) {
      pack::Reader reader(bytes[static_cast<size_t>(r)]);
      pack::get(reader, seconds[static_cast<size_t>(r)]);
      while (!reader.done()) take_point(r, reader);
    }
    add_load(seconds);
  }

  // one point's result as rank r handed it over (this rank's own too: every rank's come through the same bytes)
  void take_point(int r, pack::Reader& reader) {
    size_t i = 0;
    bool error = false;
    pack::get(reader, i);
    if (i >= labels_.size())
      throw std::runtime_error(fmt::format("rank {} handed over point {} of a sweep of {}: the ranks run different sweeps", r, i, labels_.size()));
    pack::get(reader, took_[i]);
    pack::get(reader, error);
    if (error) {
      std::string what;
      pack::get(reader, what);
      failed_[i] = fmt::format("rank {}, point {}: {}", r, labels_[i], what);
    } else {
      get_(i, reader);
    }
  }

  // `points` shared by these costs (one per point), run, handed over
  void round(const std::vector<size_t>& points, const std::vector<double>& by) {
    const auto shares = share_by_cost(by, ranks_);
    std::vector<size_t> mine;
    for (const size_t k : shares[static_cast<size_t>(me_)]) mine.push_back(points[k]);
    std::optional<interrupt::OnInterrupt> last_words;
    if (me_ == 0) last_words.emplace([this, &shares, &points] { name_points_in_hand(shares, points); });
    hand_over(mine, run_here(mine));
  }

  // A rank that dies (killed, out of memory) takes its point with it: mpirun names the rank and stops the others;
  // rank 0's last words name the points each other rank had in hand, the one it was running among them
  void name_points_in_hand(const std::vector<std::vector<size_t>>& shares, const std::vector<size_t>& points) const {
    for (int r = 1; r < ranks_; ++r) {
      const auto& share = shares[static_cast<size_t>(r)];
      std::string names;
      for (size_t k = 0; k < std::min<size_t>(share.size(), 3); ++k) names += (k ? "; " : "") + labels_[points[share[k]]];
      std::fputs(fmt::format("stepwise: stopped while rank {} had {} point(s) of this sweep in hand{}{}{}{}\n", r, share.size(),
                             share.empty() ? "" : " (run costliest first: ", names, share.size() > 3 ? "; ..." : "", share.empty() ? "" : ")")
                     .c_str(),
                 stderr);
    }
  }

  // Where the sweep has cost models and groups (points that cost alike relative to their model), each group's
  // cheapest point runs first, and the rest are shared by their model's cost times what their group's first
  // point took per unit of it (the whole first round's ratio for a group it did not reach): the models err by
  // group, and the first round costs little. The seconds are handed over with the results, so every rank
  // computes the same shares. Leaves in `rest` the points still to run, in `cost_of` their calibrated costs.
  void calibrate(std::vector<size_t>& rest, std::vector<double>& cost_of) {
    std::map<std::string, size_t> cheapest;
    for (const size_t i : rest)
      if (const auto it = cheapest.find(groups_[i]); it == cheapest.end() || weights_[i] < weights_[it->second]) cheapest[groups_[i]] = i;
    std::vector<size_t> first;
    for (const auto& [group, i] : cheapest) first.push_back(i);
    std::sort(first.begin(), first.end());
    std::vector<double> first_costs;
    for (const size_t i : first) first_costs.push_back(weights_[i]);
    round(first, first_costs);
    double seconds = 0, expected = 0;
    std::map<std::string, double> ratio;
    for (const size_t i : first) {
      seconds += took_[i];
      expected += weights_[i];
      if (weights_[i] > 0) ratio[groups_[i]] = took_[i] / weights_[i];
    }
    const double overall = expected > 0 ? seconds / expected : 1;
    std::vector<size_t> left;
    for (const size_t i : rest)
      if (!std::binary_search(first.begin(), first.end(), i)) {
        left.push_back(i);
        const auto it = ratio.find(groups_[i]);
        cost_of[i] = weights_[i] * (it != ratio.end() && it->second > 0 ? it->second : overall);
      }
    rest = std::move(left);
  }

  const StudyContext& ctx_;
  const std::vector<std::string>& labels_;
  const std::function<void(size_t)>& point_;
  const std::vector<double>& costs_;
  const std::vector<std::string>& groups_;
  const std::function<void(size_t, pack::Writer&)>& put_;
  const std::function<void(size_t, pack::Reader&)>& get_;
  const std::vector<double> weights_;
  const int ranks_, me_;
  std::vector<std::exception_ptr> errors_;
  std::vector<double> took_;  // each point's seconds (every rank's, once handed over)
  std::map<size_t, std::string> failed_;  // point -> "rank r, point label: message", in point order
};

}  // namespace

void StudyContext::run_points(const std::vector<std::string>& labels, const std::function<void(size_t)>& point,
                              const std::vector<double>& costs, const std::vector<std::string>& groups,
                              const std::function<void(size_t, pack::Writer&)>& put, const std::function<void(size_t, pack::Reader&)>& get) const {
  PointSweep(*this, labels, point, costs, groups, put, get).run();
}

}  // namespace stepwise
