#include "studies.hpp"

#include "pictures.hpp"
#include "side_by_side.hpp"

#include "solvers/method_table.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stepwise {

std::vector<std::string> method_names_where(const std::function<bool(const Method&)>& keep) {
  std::vector<std::string> names;
  for (const Method* m : methods_where(keep)) names.emplace_back(m->name);
  return names;
}

std::string sci(double v) { return std::isfinite(v) ? fmt::format("{:.2e}", v) : "—"; }

std::string add_figure(std::vector<Figure>& figures, const std::string& kind, const std::string& subject, FigureSpec spec, const std::string& caption) {
  figures.push_back({kind, subject, std::move(spec)});
  return fmt::format("![{}]({}.png)\n\n", caption, figures.back().stem());
}

std::vector<FigureSpec::Layer> by_mode(FigureSpec::Layer layer) {
  layer.series = "method";
  layer.failures = true;
  layer.hover = {{"dt", "dt"}, {"rtol", "rtol"}, {"rhs_evals", "calls of f"}, {"cpu_seconds", "CPU s"}};
  FigureSpec::Layer adaptive = layer;
  layer.where.push_back({"mode", {"fixed"}});
  adaptive.where.push_back({"mode", {"adaptive"}});
  adaptive.dashed = true;
  return {std::move(layer), std::move(adaptive)};
}

std::string_view to_string(FigureMark mark) {
  switch (mark) {
    case FigureMark::line: return "line";
    case FigureMark::points: return "points";
    case FigureMark::line_and_points: return "line+points";
    case FigureMark::star: return "star";
    case FigureMark::contour: return "contour";
    case FigureMark::front: return "front";
  }
  return "line+points";
}

nlohmann::json FigureSpec::json() const {
  nlohmann::json j{{"title", title}, {"facet", facet}, {"panels", nlohmann::json::array()}};
  for (const auto& p : panels) {
    nlohmann::json panel{{"title", p.title},   {"x_label", p.x_label},          {"y_label", p.y_label},         {"log_x", p.log_x},
                         {"log_y", p.log_y},   {"guide_slope", p.guide_slope},  {"guide_label", p.guide_label}, {"equal_aspect", p.equal_aspect}, {"symlog_x", p.symlog_x},
                         {"layers", nlohmann::json::array()}, {"lines", nlohmann::json::array()}};
    for (const auto& l : p.layers) {
      nlohmann::json where = nlohmann::json::object(), hover = nlohmann::json::array();
      for (const auto& w : l.where) where[w.column] = w.values;
      for (const auto& [column, heading] : l.hover) hover.push_back({column, heading});
      panel["layers"].push_back({{"table", l.table}, {"x", l.x}, {"y", l.y}, {"z", l.z}, {"series", l.series}, {"split", l.split}, {"split_dashed", l.split_dashed}, {"label", l.label}, {"mark", to_string(l.mark)}, {"dashed", l.dashed},
                                 {"y_of", l.y_of}, {"floor", l.floor}, {"where", where}, {"complete", l.complete}, {"failures", l.failures},
                                 {"hover", hover}, {"names", l.names}});
    }
    for (const auto& l : p.lines) panel["lines"].push_back({{"axis", std::string(1, l.axis)}, {"value", l.value}, {"label", l.label}});
    j["panels"].push_back(std::move(panel));
  }
  return j;
}

std::function<std::string(const Cell&)> shown_as(std::string spec) {
  return [spec = std::move(spec)](const Cell& cell) -> std::string {
    if (const double* v = std::get_if<double>(&cell)) return !std::isfinite(*v) || spec == "sci" ? sci(*v) : fmt::format(fmt::runtime(spec), *v);
    if (const long* n = std::get_if<long>(&cell)) return std::to_string(*n);
    return std::get<std::string>(cell);
  };
}

const Cell& cell_of(const Table& table, const std::vector<Cell>& row, std::string_view column) {
  const auto it = std::find(table.columns.begin(), table.columns.end(), column);
  if (it == table.columns.end()) throw std::invalid_argument(fmt::format("cell_of: no column '{}'", column));
  return row[static_cast<size_t>(it - table.columns.begin())];
}

std::string markdown_table(const Table& table, const std::vector<Shown>& columns, const std::function<bool(size_t row)>& keep) {
  std::vector<size_t> at;
  std::string heading = "|", rule = "|";
  for (const auto& c : columns) {
    const auto it = std::find(table.columns.begin(), table.columns.end(), c.column);
    if (c.column.empty()) at.push_back(0);
    else if (it == table.columns.end()) throw std::invalid_argument(fmt::format("markdown_table: no column '{}'", c.column));
    else at.push_back(static_cast<size_t>(it - table.columns.begin()));
    heading += fmt::format(" {} |", c.heading);
    rule += "---|";
  }
  std::string md = fmt::format("{}\n{}\n", heading, rule);
  for (size_t r = 0; r < table.rows.size(); ++r) {
    if (keep && !keep(r)) continue;
    const auto& row = table.rows[r];
    md += "|";
    for (size_t k = 0; k < columns.size(); ++k) {
      const Cell& cell = row[at[k]];
      md += fmt::format(" {} |", columns[k].of_row ? columns[k].of_row(row) : columns[k].format ? columns[k].format(cell) : shown_as("{}")(cell));
    }
    md += "\n";
  }
  return md;
}

const std::vector<Study>& studies() {
  static const std::vector<Study> all = [] {
    return std::vector<Study>{work_precision_study(),        convergence_study(),  spatial_convergence_study(), pde_scenes_study(), stability_regions_study(), energy_study(),
                              adequacy_study(),              wave_adequacy_study(), bouncing_ball_curve_study(), event_times_study(),
                              wave_stability_study(),        rigid_body_invariants_study(), contacts_study(), cloth_study(), cloth_realtime_study(), cloth_solvers_study(), continuum_cloth_study(), fluid_study(),
                              constraints_study(),           scaling_study(),               advice_study(),      pictures_study(), side_by_side_study()};
  }();
  return all;
}

}  // namespace stepwise
