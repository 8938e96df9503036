// The studies of the report: each a sweep over methods and step sizes that writes its tables.
#pragma once

#include <stepwise/run/csv.hpp>
#include <stepwise/solvers/method.hpp>
#include <stepwise/report/sweep.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace stepwise {

// an engine's frame step (s): the studies of animation's solvers run at it, the position-based ones dividing it
// into substeps
inline constexpr double engine_frame = 1.0 / 60;

// a figure declared, not drawn: which columns of which of the study's tables it plots against which, and how.
// report/plot.py draws every figure from its spec with one function (the PNG), report/interactive.py with
// another (index.html's plotly figure), both from the same lines as report/figure_spec.py reads them.
// A figure is a row of panels (copied once per value of `facet`); a panel's layers each draw one table's rows,
// a line per value of the layer's `series` column (a method: coloured by its group, marked by itself).
// how a layer draws its rows: serialised by name into figures.json (figure_spec.py's Mark reads it)
enum class FigureMark {
  line,
  points,
  line_and_points,  // "line+points"
  star,             // a point marked out (the advised method)
  contour,          // z's level 1 over the grid of x and y
  front,            // a Pareto front the study found: drawn broad and pale behind, and in index.html the methods with a
                    // point on it shown at first
};
std::string_view to_string(FigureMark mark);

struct FigureSpec {
  struct Where {
    std::string column;
    std::vector<std::string> values;  // rows kept whose cell, as the CSV writes it, is one of these
  };
  struct Layer {
    std::string table;              // the CSV stem
    std::string x, y;               // columns
    std::string series;             // the column naming each line; empty: one line
    std::vector<std::string> split; // a line per distinct value of these columns too, in its series' colour and marker
    bool split_dashed = false;      // a series' second and later lines dashed
    std::string label = "{}";       // a line's legend name: "{}" its series' value, "{column}" a split column's
    FigureMark mark = FigureMark::line_and_points;
    bool dashed = false;            // the line dashed (a "line" or "line+points" mark)
    std::string z;                  // "contour": the column whose level 1 is drawn (named after a method: in its colour)
    std::string y_of;               // "": y as it is; "abs": |y|; "minus_one": y - 1
    double floor = 0;               // > 0: a y under it (an exact 0) drawn at it, on a log axis
    std::vector<Where> where;
    std::vector<std::string> complete;  // rows kept only where each of these columns is a finite number
    bool failures = false;          // a row whose status is not ok: a cross at the panel's top, at its x
    std::vector<std::pair<std::string, std::string>> hover;  // (column, heading) shown on hover where the row has a value
    std::map<std::string, std::string> names;                // a series' legend name, in place of `label`'s
  };
  struct Line {
    char axis;                      // 'x': a vertical line at x = value; 'y': a horizontal one
    double value;
    std::string label;
  };
  struct Panel {
    std::string title;              // "{column}" shows the facet's value
    std::string x_label, y_label;
    bool log_x = false, log_y = false;
    bool symlog_x = false;          // the PNG's x linear near 0 and logarithmic past its least positive x (a 0 shown)
    std::vector<Layer> layers;
    std::vector<Line> lines;
    double guide_slope = 0;         // != 0: a dotted line y ~ x^slope through the panel's highest point at its least x
    std::string guide_label;
    bool equal_aspect = false;
  };
  std::string title;
  std::vector<Panel> panels;
  std::vector<std::string> facet;   // the panels once per distinct value of these columns (the first layer's table's)
  nlohmann::json json() const;
};

// a figure drawn by report/plot.py and report/interactive.py from the study's CSVs into stem().png: `kind` the
// study's name for it, `subject` (a scene, or empty) what it draws it for
struct Figure {
  std::string kind;
  std::string subject;
  FigureSpec spec;
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

class Model;

struct Study {
  std::string_view name;
  std::string_view title;
  std::function<StudyOutput(const StudyContext&)> run;
  // `stepwise study NAME --scene FILE`: "" where the study can run on this user's scene, else why not (the energy
  // study: no energy formula); empty for a study that runs on its own scenes only
  std::function<std::string(const StudyScene& scene, const Model& model)> scene_problem;
  // drawn on rank 0 alone, after the sweeps, into the context's `out` (pictures, videos): its points are not shared
  // among MPI ranks, and the report puts its section last
  bool drawn = false;

  bool takes_scene() const { return static_cast<bool>(scene_problem); }
};

// every study, in the report's order
const std::vector<Study>& studies();

// each study, from its own file in report/studies/ (one per study, named after it)
Study work_precision_study();
Study convergence_study();
Study spatial_convergence_study();
Study pde_scenes_study();
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
Study cloth_solvers_study();
Study continuum_cloth_study();
Study fluid_study();
Study scaling_study();
Study advice_study();
Study constraints_study();

// a sweep's layers (rows of method, mode and status): `layer` once for the fixed-step rows, drawn solid, once for
// the adaptive ones, dashed; failed rows as crosses; the setting and the calls of f on hover
std::vector<FigureSpec::Layer> by_mode(FigureSpec::Layer layer);

// adds the figure to the list; returns its Markdown (an image line and a blank line) for the section
std::string add_figure(std::vector<Figure>& figures, const std::string& kind, const std::string& subject, FigureSpec spec, const std::string& caption);

// the names of the methods `keep` keeps, in the table's order (solvers/method_table.hpp's methods_where)
std::vector<std::string> method_names_where(const std::function<bool(const Method&)>& keep);

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
