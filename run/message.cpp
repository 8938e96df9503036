#include "message.hpp"

#include "interrupt.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <utility>

namespace stepwise {

namespace {

// a code point that prints as nothing or moves the text about: C1 controls, no-break and zero-width spaces and
// joiners, the soft hyphen, bidirectional marks and embeddings, line and paragraph separators, the BOM. Echoed
// as such, a name holding one reads as its visible twin ("unknown parameter 'length' (known: ... length ...)")
bool invisible(char32_t c) {
  return (c >= 0x80 && c <= 0xa0) || c == 0xad || c == 0x34f || c == 0x61c || c == 0x180e || (c >= 0x200b && c <= 0x200f) ||
         (c >= 0x2028 && c <= 0x202f) || (c >= 0x2060 && c <= 0x206f) || c == 0xfeff || (c >= 0xfff9 && c <= 0xfffb);
}

// the UTF-8 sequence at text[i]: its code point and length, or length 0 where the bytes are not one
std::pair<char32_t, size_t> decode(std::string_view text, size_t i) {
  const auto b = [&](size_t k) { return static_cast<unsigned char>(text[i + k]); };
  const unsigned char lead = b(0);
  const size_t length = lead >= 0xf0 && lead < 0xf8 ? 4 : lead >= 0xe0 ? 3 : lead >= 0xc2 && lead < 0xe0 ? 2 : 0;
  if (length == 0 || i + length > text.size()) return {0, 0};
  char32_t c = lead & (0x7f >> length);
  for (size_t k = 1; k < length; ++k) {
    if ((b(k) & 0xc0) != 0x80) return {0, 0};
    c = (c << 6) | (b(k) & 0x3f);
  }
  return {c, length};
}

}  // namespace

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
    for (size_t k = 0; k < shown.size(); ++k) {
      const char c = shown[k];
      const auto u = static_cast<unsigned char>(c);
      if (c == '\n') out += "\\n";
      else if (c == '\t') out += "\\t";
      else if (c == '\r') out += "\\r";
      else if (u < 0x20 || u == 0x7f) out += fmt::format("\\x{:02x}", u);
      else if (u < 0x80) out += c;
      else if (const auto [point, length] = decode(shown, k); length == 0) out += fmt::format("\\x{:02x}", u);
      else {
        if (invisible(point)) out += fmt::format("\\u{{{:04x}}}", static_cast<unsigned>(point));
        else out += shown.substr(k, length);
        k += length - 1;
      }
    }
    if (shown.size() < word.size()) out += fmt::format("...({} characters)", word.size());
    if (end < text.size()) out += ' ';
    i = end + 1;
  }
  return out;
}

void print_error(std::string_view command, std::string_view message) {
  interrupt::settle();  // an interruption says its own line
  const std::string line = fmt::format("stepwise{}{}: {}\n", command.empty() ? "" : " ", command, one_line(message));
  std::fwrite(line.data(), 1, line.size(), stderr);
  std::fflush(stderr);
}

}  // namespace stepwise
