#include "message.hpp"

#include <fmt/format.h>

#include <cstdio>

namespace stepwise {

std::string one_line(std::string_view text) {
  constexpr size_t longest = 160, kept = 64;
  std::string out;
  size_t i = 0;
  while (i < text.size()) {
    // the next run without a space: kept whole, or cut
    size_t end = i;
    while (end < text.size() && text[end] != ' ') ++end;
    const std::string_view word = text.substr(i, end - i);
    const std::string_view shown = word.size() > longest ? word.substr(0, kept) : word;
    for (const char c : shown) {
      const auto u = static_cast<unsigned char>(c);
      if (c == '\n') out += "\\n";
      else if (c == '\t') out += "\\t";
      else if (c == '\r') out += "\\r";
      else if (u < 0x20 || u == 0x7f) out += fmt::format("\\x{:02x}", u);
      else out += c;
    }
    if (shown.size() < word.size()) out += fmt::format("...({} characters)", word.size());
    if (end < text.size()) out += ' ';
    i = end + 1;
  }
  return out;
}

void print_error(std::string_view command, std::string_view message) {
  const std::string line = fmt::format("stepwise{}{}: {}\n", command.empty() ? "" : " ", command, one_line(message));
  std::fwrite(line.data(), 1, line.size(), stderr);
  std::fflush(stderr);
}

}  // namespace stepwise
