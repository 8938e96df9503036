#include "integrator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <ctime>
#include <string>
#include <utility>

namespace stepwise {

std::string_view to_string(Status status) {
  switch (status) {
    case Status::ok: return "ok";
    case Status::diverged: return "diverged";
    case Status::failed: return "failed";
  }
  return "failed";
}

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

namespace {
thread_local std::atomic<double>* run_workers = nullptr;  // the run on this thread's count of its workers' CPU time
}  // namespace

std::atomic<double>* worker_cpu_seconds() { return run_workers; }

// cpu_seconds: this thread's CPU time in the run, and its workers' (WorkerCpuTime); a run inside another (a
// reference the method takes) hands its workers' time on to the outer run's count too
RunResult Integrator::integrate(const OdeSystem& system, double t0, const Eigen::VectorXd& y0, std::span<const double> t_out) const {
  std::atomic<double> workers{0};
  std::atomic<double>* const outer = std::exchange(run_workers, &workers);
  struct Restore {
    std::atomic<double>* outer;
    std::atomic<double>& workers;
    ~Restore() {
      run_workers = outer;
      if (outer) outer->fetch_add(workers.load());
    }
  } restore{outer, workers};
  const double start = thread_cpu_seconds();
  RunResult result = solve(system, t0, y0, t_out);
  result.stats.cpu_seconds = thread_cpu_seconds() - start + workers.load();
  return result;
}

}  // namespace stepwise
