// The report's study: stability regions: each method's region in the complex plane against the scenes' spectra.
#include "report/studies/study_scenes.hpp"

#include <optional>

namespace stepwise {
namespace {

constexpr long steps = 2000;  // a probe's steps, from which a run must stay within 1e6 of its start

struct SpectrumScene {
  std::string label;
  std::shared_ptr<const Model> model;
  Eigen::VectorXd y0;
  std::function<bool(std::string_view method, double dt)> bounded;  // the measured side
};

// a method's predicted and measured largest stable step on a scene
struct Limit {
  size_t scene;
  std::string method;
  double predicted = NAN, measured = NAN;
};

// the scenes whose spectra are drawn: the user's, or the standing wave's grid from a random field (every mode
// excited) and the cloth's stability sheet from rest
std::vector<SpectrumScene> spectrum_scenes(const StudyContext& ctx) {
  std::vector<SpectrumScene> scenes;
  if (ctx.scenes) {
    // the user's scene: its exact Jacobian's spectrum at the start, and runs from its initial state
    for (const auto& scene : *ctx.scenes) {
      std::shared_ptr<const Model> model = scene_model(scene);
      scenes.push_back({scene.label, model, model->initial_state(), [model](std::string_view method, double dt) {
                          return stays_bounded(*model, method, model->initial_state(), dt, steps);
                        }});
    }
  } else {
    const auto all = ode_scenes();
    const auto scene = *std::find_if(all.begin(), all.end(), [](const StudyScene& s) { return s.label == "standing-wave"; });
    std::shared_ptr<const Model> model = make_model(scene.model, scene.params);
    const WaveGridView grid = *model->as<WaveGridView>();
    scenes.push_back({scene.label, model, model->initial_state(), [grid](std::string_view method, double dt) {
                        return wave_stays_bounded(method, grid.points, grid.spacing, grid.c, grid.mu, steps)(dt);
                      }});
    std::shared_ptr<const Model> sheet = stability_sheet(1000);
    scenes.push_back({"cloth-sheet", sheet, sheet->initial_state(), [sheet](std::string_view method, double dt) {
                        return stays_bounded(*sheet, method, sheet->initial_state(), dt, steps);
                      }});
  }
  return scenes;
}

// the figure's plane, per scene: the spectrum times rk4's predicted step h (and 1.5 h) into `plane_spectrum`, and
// |R(z)| of each region's method on a grid reaching past the farthest h lambda into a table (the figure draws
// its level 1), which is returned
Table region_plane(const std::vector<SpectrumScene>& scenes, const std::vector<Eigen::VectorXcd>& spectra, const std::vector<Limit>& limits,
                   const std::vector<std::string>& region_methods, Table& plane_spectrum) {
  const size_t grid = 81;
  std::vector<std::string> plane_columns{"scene", "re", "im"};
  std::vector<std::complex<double> (*)(std::complex<double>)> regions;  // each region method's R
  for (const auto& method : region_methods) {
    plane_columns.push_back(method);
    regions.push_back(find_method(method)->stability.R);
  }
  Table plane{plane_columns, {}};
  for (size_t i = 0; i < scenes.size(); ++i) {
    const auto rk4 = std::find_if(limits.begin(), limits.end(), [&](const Limit& l) { return l.scene == i && l.method == "rk4"; });
    const double h = rk4->predicted;
    double reach = 3.2;
    for (const auto& lambda : spectra[i]) {
      reach = std::max(reach, 1.15 * std::abs(h * lambda));
      for (const auto& [step, scale] : {std::pair{"h", 1.0}, {"1.5 h", 1.5}})
        plane_spectrum.rows.push_back({scenes[i].label, std::string(step), scale * h * lambda.real(), scale * h * lambda.imag()});
    }
    for (size_t a = 0; a < grid; ++a)
      for (size_t b = 0; b < grid; ++b) {
        const std::complex<double> z(-reach + 1.6 * reach * static_cast<double>(a) / (grid - 1), -reach + 2 * reach * static_cast<double>(b) / (grid - 1));
        std::vector<Cell> row{scenes[i].label, z.real(), z.imag()};
        for (const auto R : regions) row.push_back(std::abs(R(z)));
        plane.rows.push_back(std::move(row));
      }
  }
  return plane;
}

// the finding: rk4's measured limits against its predicted ones; empty where it has none
std::optional<std::string> rk4_finding(const Table& table) {
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& row : table.rows)
    if (const double r = std::get<double>(cell_of(table, row, "measured_over_spectrum"));
        std::get<std::string>(cell_of(table, row, "method")) == "rk4" && std::isfinite(r)) {
      lo = std::min(lo, r);
      hi = std::max(hi, r);
    }
  if (!std::isfinite(lo)) return std::nullopt;
  return fmt::format("**A step fails when h lambda leaves the method's stability region**: rk4's largest stable step, found by "
                     "bisection, is {:.3f} to {:.3f} times the one its region and the scene's spectrum predict.", lo, hi);
}

StudyOutput stability_regions(const StudyContext& ctx) {
  const std::vector<SpectrumScene> scenes = spectrum_scenes(ctx);
  // the regions drawn: the fixed-step methods with a stability function R(z) (one-step methods on y' = lambda y)
  const std::vector<std::string> region_methods =
      method_names_where([](const Method& m) { return m.stability.R != nullptr && m.stepping == Stepping::fixed; });

  std::vector<std::string> labels;
  for (const auto& s : scenes) labels.push_back(s.label + " spectrum");
  const auto spectra = ctx.sweep<Eigen::VectorXcd>(labels, [&](size_t i) { return jacobian_spectrum(*scenes[i].model, 0, scenes[i].y0); });

  std::vector<Limit> limits;
  labels.clear();
  for (size_t i = 0; i < scenes.size(); ++i)
    for (const auto& method : region_methods) {
      limits.push_back({i, method, *spectrum_stable_dt(method, spectra[i])});
      labels.push_back(fmt::format("{} {}", scenes[i].label, method));
    }
  const auto measured = ctx.sweep<double>(labels, [&](size_t k) {
    const Limit& l = limits[k];
    // an A-stable method (no largest stable step) is not probed: implicit Euler's Newton solves on 578 unknowns
    // would cost more than the rest of the study
    if (!std::isfinite(l.predicted) || l.predicted <= 0) return std::numeric_limits<double>::quiet_NaN();
    const auto& s = scenes[l.scene];
    return bisect_stability([&](double dt) { return s.bounded(l.method, dt); }, l.predicted / 4, l.predicted * 16,
                            tolerance::stability_bisection_width);
  });

  Table spectrum{{"scene", "re", "im"}, {}};
  for (size_t i = 0; i < scenes.size(); ++i)
    for (const auto& lambda : spectra[i]) spectrum.rows.push_back({scenes[i].label, lambda.real(), lambda.imag()});
  Table plane_spectrum{{"scene", "step", "re", "im"}, {}};
  Table plane = region_plane(scenes, spectra, limits, region_methods, plane_spectrum);
  Table table{{"scene", "method", "spectrum_dt", "measured_dt", "measured_over_spectrum"}, {}};
  StudyOutput out;
  const std::string subject = ctx.scenes ? fmt::format("The spectrum of {}'s exact Jacobian at its initial state is drawn", scenes.front().label)
                                         : std::string("The spectra of the standing wave's 17^2 grid (578 unknowns, mu = 0.5) and of the cloth's 8 x 8 "
                                                       "stability sheet (c = 1000 N/m) are drawn");
  FigureSpec::Panel panel{.title = "{scene}: the spectrum times rk4's predicted step h", .x_label = "Re z", .y_label = "Im z",
                          .lines = {{'x', 0, ""}, {'y', 0, ""}}, .equal_aspect = true};
  for (const auto& method : region_methods)
    panel.layers.push_back({.table = "stability_plane", .x = "re", .y = "im", .label = "|R(z)| = 1, " + method, .mark = FigureMark::contour, .z = method});
  for (const auto& [step, what] : {std::pair{"h", "h lambda, h = rk4's predicted limit"}, {"1.5 h", "at 1.5 h"}})
    panel.layers.push_back({.table = "stability_plane_spectrum", .x = "re", .y = "im", .label = what, .mark = FigureMark::points, .where = {{"step", {step}}}});
  FigureSpec spec{.title = "Stability regions |R(z)| <= 1 and the scenes' spectra", .panels = {std::move(panel)}, .facet = {"scene"}};
  out.markdown = fmt::format(
      "Why a step fails: a one-step method multiplies each eigen-component of a linear(ised) system by R(h lambda) per step, so it is "
      "stable while every h lambda of the Jacobian's spectrum lies in its region |R(z)| <= 1. {} times rk4's largest stable "
      "step predicted from them, over the regions of explicit Euler, rk4 and implicit Euler (the whole plane outside the disc about 1). "
      "Predicted: the largest h keeping every h lambda in the region; measured: bisection to 0.1% on {} steps (from a random field for "
      "the wave, from rest for the sheet) staying within 1e6 of the start.\n\n{}",
      subject, steps, add_figure(out.figures, "stability_regions", "", std::move(spec), "Stability regions and the scenes' spectra"));
  for (size_t k = 0; k < limits.size(); ++k) {
    const Limit& l = limits[k];
    const double ratio = measured[k] / l.predicted;
    table.rows.push_back({scenes[l.scene].label, l.method, l.predicted, measured[k], ratio});
  }
  const auto predicted = [](const Cell& cell) {
    const double dt = std::get<double>(cell);
    return std::isinf(dt) ? std::string("any (A-stable)") : fmt::format("{:.4g}", dt);
  };
  out.markdown += markdown_table(table, {{"scene", "scene"},
                                         {"method", "method"},
                                         {"spectrum_dt", "predicted from the spectrum (s)", predicted},
                                         {"measured_dt", "measured (s)", shown_as("{:.4g}")},
                                         {"measured_over_spectrum", "measured / predicted", shown_as("{:.3f}")}});
  out.markdown += "\nrk4's measured limits match the spectrum's; explicit Euler's probe finds several times its prediction (up to the "
                  "bracket's 16): near its limit its growth per step, |1 + h lambda| - 1, is so small on the weakly damped modes that "
                  "2000 steps do not show it, the cloth study's finding. Symplectic Euler has no R(z): it maps (x, v) pairs, and on an undamped oscillator it is stable for h omega < 2, "
                  "the segment of the imaginary axis |z| < 2 (the cloth study's table).\n\n";
  if (auto finding = rk4_finding(table)) out.findings.push_back(std::move(*finding));
  out.tables = {{"stability_spectrum", std::move(spectrum)}, {"stability_limits", std::move(table)},
                {"stability_plane", std::move(plane)}, {"stability_plane_spectrum", std::move(plane_spectrum)}};
  return out;
}

}  // namespace

Study stability_regions_study() { return {.name = "stability-regions", .title = "Stability: the methods' regions against the scenes' spectra", .run = stability_regions, .scene_problem = [](const StudyScene&, const Model&) { return std::string(); }}; }

}  // namespace stepwise
