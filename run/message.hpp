// What stepwise says when it refuses or fails: always one line. A message quotes the user's own values (a file
// name, a key, a model name), which may hold a newline or run to megabytes: control characters are escaped
// and a long unbroken run of characters is cut, with its length said.
#pragma once

#include <string>
#include <string_view>

namespace stepwise {

// `text` on one line: control characters as \n, \t or \xHH, any run of more than 160 characters without a
// space cut to its first 64 and "...(N characters)"
std::string one_line(std::string_view text);

// "stepwise <command>: <message>" on stderr, through one_line
void print_error(std::string_view command, std::string_view message);

}  // namespace stepwise
