// The studies of the report: each a sweep over methods and step sizes that writes its tables.
#pragma once

#include "csv.hpp"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace stepwise {

struct StudyOutput {
  std::vector<std::pair<std::string, Table>> tables;  // file stem -> table (written as stem.csv)
  std::string markdown;                               // the study's section of report.md
};

struct Study {
  std::string_view name;
  std::string_view title;
  std::function<StudyOutput(bool quick)> run;
};

const std::vector<Study>& studies();

}  // namespace stepwise
