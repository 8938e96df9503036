// The memory budget every refusal keeps (a method's dense matrices, a particle count, a render's frames): a run
// may plan on at most half of this machine's physical memory. Models, methods and commands all keep it.
#pragma once

#include <string>

namespace stepwise {

// this machine's physical memory, the bound memory checks are made against (the smallest of the machine's, its
// cgroup's memory.max and $STEPWISE_MEMORY in bytes)
double physical_memory_bytes();

// the budget, and the budget in its words ("more than half of this machine's 23.5 GiB, the most a run may plan on")
bool over_memory_budget(double bytes);
std::string memory_budget_text();

}  // namespace stepwise
