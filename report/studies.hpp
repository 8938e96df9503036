// The studies of the report: each a sweep over methods and step sizes that writes its tables.
#pragma once

#include "run/csv.hpp"
#include "sweep.hpp"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace stepwise {

// a figure drawn by report/plot.py from the study's CSVs into stem().png: `kind` names plot.py's function,
// `subject` (a scene, or empty) what it draws it for
struct Figure {
  std::string kind;
  std::string subject;
  std::string stem() const { return subject.empty() ? kind : kind + "_" + subject; }
};

struct StudyOutput {
  std::vector<std::pair<std::string, Table>> tables;  // file stem -> table (written as stem.csv)
  std::string markdown;                               // the study's section of report.md
  std::vector<Figure> figures;                        // drawn after the tables are written, shown after the text
};

struct Study {
  std::string_view name;
  std::string_view title;
  std::function<StudyOutput(const StudyContext&)> run;
};

// every study, in the report's order
const std::vector<Study>& studies();

// the studies of accuracy against step and cost (study_accuracy.cpp)
std::vector<Study> accuracy_studies();

// adds the figure to the list; returns its Markdown (an image line and a blank line) for the section
std::string add_figure(std::vector<Figure>& figures, const std::string& kind, const std::string& subject, const std::string& caption);

// a number in scientific notation with 3 digits, or a dash for nan and inf
std::string sci(double v);

}  // namespace stepwise
