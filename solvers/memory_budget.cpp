#include "memory_budget.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <string>

#include <unistd.h>

namespace stepwise {

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

}  // namespace stepwise
