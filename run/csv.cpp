#include "csv.hpp"

#include <fmt/format.h>

namespace stepwise {

namespace {
std::string cell_text(const Cell& cell) {
  if (const auto* d = std::get_if<double>(&cell)) return fmt::format("{:.17g}", *d);
  if (const auto* l = std::get_if<long>(&cell)) return std::to_string(*l);
  const auto& s = std::get<std::string>(cell);
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string quoted = "\"";
  for (char c : s) {
    quoted += c;
    if (c == '"') quoted += c;  // a quote inside a quoted field is doubled
  }
  quoted += '"';
  return quoted;
}
}  // namespace

std::string csv_row(const std::vector<Cell>& row) {
  std::string out;
  for (size_t i = 0; i < row.size(); ++i) {
    if (i) out += ',';
    out += cell_text(row[i]);
  }
  return out + '\n';
}

std::string to_csv(const Table& table) {
  std::string out = csv_row(std::vector<Cell>(table.columns.begin(), table.columns.end()));
  for (const auto& row : table.rows) out += csv_row(row);
  return out;
}

}  // namespace stepwise
