#include "sweep.hpp"

#include <fmt/format.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <thread>

namespace stepwise {

Progress::Progress() : terminal_(isatty(STDERR_FILENO) != 0) {}

void Progress::begin_study(std::string_view name) {
  std::lock_guard lock(mutex_);
  study_ = name;
  total_ = done_ = last_line_ = 0;
  total_weight_ = done_weight_ = 0;
  if (!terminal_) fmt::print(stderr, "stepwise: study {} ...\n", study_);
}

void Progress::begin_sweep(size_t points, double weight) {
  std::lock_guard lock(mutex_);
  total_ += points;
  total_weight_ += weight;
  if (done_ == 0) sweep_start_ = std::chrono::steady_clock::now();
}

void Progress::point_done(const std::string& label, double weight) {
  std::lock_guard lock(mutex_);
  ++done_;
  done_weight_ += weight;
  draw(label);
}

void Progress::draw(const std::string& label) {
  if (total_ == 0) return;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - sweep_start_).count();
  const double left = done_weight_ > 0 ? elapsed / done_weight_ * std::max(0.0, total_weight_ - done_weight_) : 0.0;
  if (terminal_) {
    constexpr int width = 24;
    const int filled = static_cast<int>(width * done_ / total_);
    std::string shown = label.size() > 40 ? label.substr(0, 39) + "~" : label;
    fmt::print(stderr, "\r\033[K{} [{}{}] {}/{} {} ~{:.0f} s left", study_, std::string(filled, '#'), std::string(width - filled, '.'),
               done_, total_, shown, left);
  } else if (done_ == total_ || (done_ - last_line_) * 10 >= total_) {
    // a line each tenth of the sweep: a log keeps the progress without a line per point
    last_line_ = done_;
    fmt::print(stderr, "stepwise:   {}/{} points, last {}, ~{:.0f} s left\n", done_, total_, label, left);
  }
}

void Progress::end_study(double seconds) {
  std::lock_guard lock(mutex_);
  if (terminal_) fmt::print(stderr, "\r\033[Kstepwise: study {} {:.1f} s\n", study_, seconds);
  else fmt::print(stderr, "stepwise: study {} done in {:.1f} s\n", study_, seconds);
}

void StudyContext::run_points(const std::vector<std::string>& labels, const std::function<void(size_t)>& point,
                              const std::vector<double>& costs) const {
  const auto cost = [&](size_t i) { return costs.empty() ? 1.0 : costs[i]; };
  // the order the points are taken in: the costliest first
  std::vector<size_t> order(labels.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  if (!costs.empty()) std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return costs[a] > costs[b]; });
  double total = 0;
  for (size_t i = 0; i < labels.size(); ++i) total += cost(i);
  if (progress) progress->begin_sweep(labels.size(), total);
  std::atomic<size_t> next{0};
  std::vector<std::exception_ptr> errors(labels.size());
  auto worker = [&] {
    for (size_t k = next++; k < labels.size(); k = next++) {
      const size_t i = order[k];
      try {
        point(i);
      } catch (...) {
        errors[i] = std::current_exception();
      }
      if (progress) progress->point_done(labels[i], cost(i));
    }
  };
  const size_t n = std::min(labels.size(), static_cast<size_t>(std::max(threads, 1)));
  std::vector<std::jthread> pool;
  for (size_t k = 1; k < n; ++k) pool.emplace_back(worker);
  worker();
  pool.clear();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace stepwise
