// A table of named columns written as CSV: trajectories, study sweeps.
#pragma once

#include <string>
#include <variant>
#include <vector>

namespace stepwise {

using Cell = std::variant<double, long, std::string>;

struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<Cell>> rows;
};

// one row of CSV, its newline included (a row streamed to its file as it is computed)
std::string csv_row(const std::vector<Cell>& row);

// CSV text: a header row, doubles with 17 significant digits so they read back exactly
std::string to_csv(const Table& table);

}  // namespace stepwise
