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
  // (the models overestimate: measured, the quick report's work-precision points took 0.4 of their expected
  // time, summed, with early estimates 2-2.6 times the truth at 1e-9 s a unit; on a machine 1.85 times slower
  // the full report's work-precision lines said 0.45-0.50 of the truth, hence the slowness measured at the start)
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

void StudyContext::run_points(const std::vector<std::string>& labels, const std::function<void(size_t)>& point,
                              const std::vector<double>& costs, const std::vector<std::string>& groups,
                              const std::function<void(size_t, pack::Writer&)>& put, const std::function<void(size_t, pack::Reader&)>& get) const {
  const std::vector<double> weights = costs.empty() ? std::vector<double>(labels.size(), 1.0) : costs;
  const int ranks = distribute ? ranks::size() : 1, me = distribute ? ranks::rank() : 0;
  std::vector<std::exception_ptr> errors(labels.size());
  std::vector<double> took(labels.size(), 0.0);  // each point's seconds (every rank's, once handed over)

  // these points (the costliest first) on this rank's threads; the seconds until the last is done
  const auto run_here = [&](const std::vector<size_t>& mine) {
    const size_t n = std::min(mine.size(), static_cast<size_t>(std::max(threads, 1)));
    if (progress) {
      std::vector<double> my_weights;
      std::vector<std::string> my_groups;
      for (const size_t i : mine) {
        my_weights.push_back(weights[i]);
        if (!groups.empty()) my_groups.push_back(groups[i]);
      }
      progress->begin_sweep(my_weights, my_groups, static_cast<int>(std::max<size_t>(n, 1)), !costs.empty());
    }
    const auto start = std::chrono::steady_clock::now();
    std::atomic<size_t> next{0};
    auto worker = [&] {
      for (size_t k = next++; k < mine.size(); k = next++) {
        const size_t i = mine[k];
        const auto begun = std::chrono::steady_clock::now();
        if (progress) progress->point_started(k);
        try {
          point(i);
        } catch (...) {
          errors[i] = std::current_exception();
        }
        took[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - begun).count();
        if (progress) progress->point_done(k, labels[i], took[i]);
      }
    };
    std::vector<std::jthread> pool;
    for (size_t k = 1; k < n; ++k) pool.emplace_back(worker);
    worker();
    pool.clear();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const auto add_load = [&](const std::vector<double>& seconds) {
    if (!load) return;
    load->seconds.resize(std::max(load->seconds.size(), seconds.size()));
    for (size_t r = 0; r < seconds.size(); ++r) load->seconds[r] += seconds[r];
  };

  if (ranks == 1) {
    add_load({run_here(share_by_cost(weights, 1)[0])});  // every point, the costliest first
    for (const auto& e : errors)
      if (e) std::rethrow_exception(e);
    return;
  }
  std::vector<size_t> all(labels.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;

  // Under mpirun: hand this rank's results to every rank (its busy time, then for each point its index, its
  // seconds, whether it failed, and the error's message or the result) and take theirs
  std::map<size_t, std::string> failed;  // point -> "rank r, point label: message", in point order
  const auto message = [](const std::exception_ptr& e) {
    try {
      std::rethrow_exception(e);
    } catch (const std::exception& x) {
      return std::string(x.what());
    } catch (...) {
      return std::string("an unknown exception");
    }
  };
  const auto hand_over = [&](const std::vector<size_t>& mine, double busy) {
    pack::Writer w;
    pack::put(w, busy);
    for (const size_t i : mine) {
      pack::put(w, i);
      pack::put(w, took[i]);
      pack::put(w, errors[i] != nullptr);
      if (errors[i]) pack::put(w, message(errors[i]));
      else put(i, w);
    }
    const std::vector<std::string> bytes = ranks::all_gather(w.bytes());
    std::vector<double> seconds(static_cast<size_t>(ranks));
    for (int r = 0; r < ranks; ++r) {
      pack::Reader reader(bytes[static_cast<size_t>(r)]);
      pack::get(reader, seconds[static_cast<size_t>(r)]);
      while (!reader.done()) {
        size_t i = 0;
        bool error = false;
        pack::get(reader, i);
        if (i >= labels.size()) throw std::runtime_error(fmt::format("rank {} handed over point {} of a sweep of {}: the ranks run different sweeps", r, i, labels.size()));
        pack::get(reader, took[i]);
        pack::get(reader, error);
        if (error) {
          std::string what;
          pack::get(reader, what);
          failed[i] = fmt::format("rank {}, point {}: {}", r, labels[i], what);
        } else {
          get(i, reader);  // this rank's own too: every rank's results come through the same bytes
        }
      }
    }
    add_load(seconds);
  };
  // `points` shared by these costs (one per point), run, handed over
  const auto round = [&](const std::vector<size_t>& points, const std::vector<double>& by) {
    const auto shares = share_by_cost(by, ranks);  // kept: a range-for over a temporary's element would dangle
    std::vector<size_t> mine;
    for (const size_t k : shares[static_cast<size_t>(me)]) mine.push_back(points[k]);
    // a rank that dies (killed, out of memory) takes its point with it: mpirun names the rank and stops the
    // others; rank 0's last words name the points each other rank had in hand, the one it was running among them
    std::optional<interrupt::OnInterrupt> last_words;
    if (me == 0)
      last_words.emplace([&labels, &shares, &points, ranks] {
        for (int r = 1; r < ranks; ++r) {
          const auto& share = shares[static_cast<size_t>(r)];
          std::string names;
          for (size_t k = 0; k < std::min<size_t>(share.size(), 3); ++k) names += (k ? "; " : "") + labels[points[share[k]]];
          std::fputs(fmt::format("stepwise: stopped while rank {} had {} point(s) of this sweep in hand{}{}{}{}\n", r, share.size(),
                                 share.empty() ? "" : " (run costliest first: ", names, share.size() > 3 ? "; ..." : "", share.empty() ? "" : ")")
                         .c_str(),
                     stderr);
        }
      });
    hand_over(mine, run_here(mine));
  };

  // Where the sweep has cost models and groups (points that cost alike relative to their model), each group's
  // cheapest point runs first, and the rest are shared by their model's cost times what their group's first
  // point took per unit of it (the whole first round's ratio for a group it did not reach): the models err by
  // group (measured: a rank 1.2 times the mean on the quick report with the models alone), and the first round
  // costs little. The seconds are handed over with the results, so every rank computes the same shares.
  std::vector<size_t> rest = all;
  std::vector<double> cost_of(weights);
  if (!costs.empty() && !groups.empty()) {
    std::map<std::string, size_t> cheapest;
    for (const size_t i : all)
      if (const auto it = cheapest.find(groups[i]); it == cheapest.end() || weights[i] < weights[it->second]) cheapest[groups[i]] = i;
    std::vector<size_t> first;
    for (const auto& [group, i] : cheapest) first.push_back(i);
    std::sort(first.begin(), first.end());
    std::vector<double> first_costs;
    for (const size_t i : first) first_costs.push_back(weights[i]);
    round(first, first_costs);
    double seconds = 0, expected = 0;
    std::map<std::string, double> ratio;
    for (const size_t i : first) {
      seconds += took[i];
      expected += weights[i];
      if (weights[i] > 0) ratio[groups[i]] = took[i] / weights[i];
    }
    const double overall = expected > 0 ? seconds / expected : 1;
    rest.clear();
    for (const size_t i : all)
      if (!std::binary_search(first.begin(), first.end(), i)) {
        rest.push_back(i);
        const auto it = ratio.find(groups[i]);
        cost_of[i] = weights[i] * (it != ratio.end() && it->second > 0 ? it->second : overall);
      }
  }
  std::vector<double> rest_costs;
  for (const size_t i : rest) rest_costs.push_back(cost_of[i]);
  round(rest, rest_costs);
  if (!failed.empty()) throw SweepError(failed.begin()->second);
}

}  // namespace stepwise
