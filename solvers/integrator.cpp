#include "integrator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <string>

#include <unistd.h>

namespace stepwise {

std::string_view to_string(Status status) {
  switch (status) {
    case Status::ok: return "ok";
    case Status::diverged: return "diverged";
    case Status::failed: return "failed";
  }
  return "failed";
}

double physical_memory_bytes() {
  static const double bytes = [] {
    double memory = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
    // a container's or a batch job's share (cgroup v2), where it is smaller
    if (std::ifstream limit("/sys/fs/cgroup/memory.max"); limit) {
      std::string text;
      limit >> text;
      if (!text.empty() && text != "max") memory = std::min(memory, std::strtod(text.c_str(), nullptr));
    }
    // what the user says the run may assume (a node shared with other jobs; the fuzzer's own limit)
    if (const char* env = std::getenv("STEPWISE_MEMORY"))
      if (const double said = std::strtod(env, nullptr); said > 0) memory = std::min(memory, said);
    return memory;
  }();
  return bytes;
}

bool over_memory_budget(double bytes) { return bytes > 0.5 * physical_memory_bytes(); }

std::string memory_budget_text() {
  return fmt::format("more than half of this machine's {:.3g} GiB, the most a run may plan on", physical_memory_bytes() / 0x1p30);
}

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

RunResult Integrator::integrate(const OdeSystem& system, double t0, const Eigen::VectorXd& y0, std::span<const double> t_out) const {
  const double start = thread_cpu_seconds();
  RunResult result = solve(system, t0, y0, t_out);
  result.stats.cpu_seconds = thread_cpu_seconds() - start;
  return result;
}

}  // namespace stepwise
