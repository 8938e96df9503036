// The studies of the report: each a sweep over methods and step sizes that writes its tables.
#pragma once

#include "run/csv.hpp"
#include "sweep.hpp"

#include <filesystem>
#include <functional>
#include <optional>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace stepwise {

// a figure declared rather than drawn by a function of its own: which columns of which of the study's tables it
// plots against which, a line per value of `series` (a method: coloured by its group, marked by itself), a panel
// per value of `facet`, on log or linear axes, with reference lines. report/plot.py draws every declared figure
// with one function, as the PNG and as index.html's interactive figure (report/interactive.py), alike
struct FigureSpec {
  struct Curve {
    std::string column;         // y
    std::string label;          // added to the series' name in the legend ("predicted"), or the line's name
    bool points_only = false;   // markers without a line (measurements beside a predicted line)
  };
  struct Line {
    char axis;                  // 'x': a vertical line at x = value; 'y': a horizontal one
    double value;
    std::string label;
  };
  std::string table;            // the CSV stem
  std::string x;
  std::vector<Curve> y;
  std::string y_label, x_label, title;
  std::string series;           // the column naming each line ("method"); empty: a line per curve
  std::string facet;            // the column naming each panel; empty: one panel
  bool log_x = false, log_y = false;
  std::vector<Line> lines;
  std::string series_label;           // a series' name in the legend, "{}" standing for its value; empty: the value
  std::vector<std::string> complete;  // rows kept only where each of these columns is a finite number
  nlohmann::json json() const;
};

// a figure drawn by report/plot.py from the study's CSVs into stem().png: `kind` names plot.py's function (or
// "declared", drawn from `spec`), `subject` (a scene, or empty) what it draws it for
struct Figure {
  std::string kind;
  std::string subject;
  std::optional<FigureSpec> spec;
  std::string stem() const { return subject.empty() ? kind : kind + "_" + subject; }
};

struct StudyOutput {
  std::vector<std::pair<std::string, Table>> tables;  // file stem -> table (written as stem.csv)
  std::string markdown;                               // the study's section of report.md
  std::vector<Figure> figures;                        // drawn after the tables are written, shown after the text
  // what the study found, for the report's opening summary: a sentence each, whose numbers with a decimal point
  // are values of the study's own tables as they are shown (check_report.py holds them to the CSVs)
  std::vector<std::string> findings;
};

struct Study {
  std::string_view name;
  std::string_view title;
  std::function<StudyOutput(const StudyContext&)> run;
};

// every study, in the report's order
const std::vector<Study>& studies();

// each study, from its own file in report/studies/ (one per study, named after it)
Study work_precision_study();
Study convergence_study();
Study stability_regions_study();
Study energy_study();
Study adequacy_study();
Study wave_adequacy_study();
Study bouncing_ball_curve_study();
Study event_times_study();
Study wave_stability_study();
Study rigid_body_invariants_study();
Study contacts_study();
Study cloth_study();
Study cloth_realtime_study();
Study fluid_study();
Study scaling_study();
Study advice_study();

// adds the figure to the list; returns its Markdown (an image line and a blank line) for the section
std::string add_figure(std::vector<Figure>& figures, const std::string& kind, const std::string& subject, const std::string& caption);
// a declared figure, drawn into `stem`.png
std::string add_figure(std::vector<Figure>& figures, const std::string& stem, FigureSpec spec, const std::string& caption);

// a number in scientific notation with 3 digits, or a dash for nan and inf
std::string sci(double v);

// a column of a study's Markdown table: the Table's column it shows (by name), its heading, and how a cell is
// shown (empty: as {} shows it); the table and its CSV are then one Table, and every number shown is the CSV's
struct Shown {
  std::string column;  // empty: the column is shown from the whole row by `of_row`
  std::string heading;
  std::function<std::string(const Cell& cell)> format;
  std::function<std::string(const std::vector<Cell>& row)> of_row;  // a column showing several of the Table's
};
// the cell of `row` in `table`'s column `column` (std::invalid_argument if it has none)
const Cell& cell_of(const Table& table, const std::vector<Cell>& row, std::string_view column);
// a number cell with fmt's format `spec` ("{:.3g}"), `sci` for sci(), a dash where it is not finite; a text or
// integer cell as it is
std::function<std::string(const Cell&)> shown_as(std::string spec);
// the Markdown table of `table`'s rows (those `keep` keeps, by index, where given), showing `columns`
// (std::invalid_argument for a column it lacks)
std::string markdown_table(const Table& table, const std::vector<Shown>& columns, const std::function<bool(size_t row)>& keep = {});

}  // namespace stepwise
