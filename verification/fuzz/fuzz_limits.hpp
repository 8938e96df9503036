// What both libFuzzer targets share: the memory the budgets judge against (what the fuzzer's own RSS limit of
// 2 GiB lets a run have), set once at start, and the largest input either takes.
#pragma once

#include <cstddef>
#include <cstdlib>

namespace stepwise::fuzz {

inline int limit_memory() { return setenv("STEPWISE_MEMORY", "1.5e9", 1); }

inline constexpr std::size_t largest_input = std::size_t{1} << 16;

}  // namespace stepwise::fuzz
