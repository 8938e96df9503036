// The report's study: the shipped PDE scenes (model = "pde", written as text) asked what a user asks of their own:
// each explicit method's largest stable step, predicted from the discretised operator's spectrum and found by
// bisection, in the units the grid sets (h^2 / D for diffusion, h / c for advection); and the cheapest method for
// an error at t_end, measured. Both are `stepwise advise`'s (report/advise.hpp) within a budget a scene.
#include "models/pde.hpp"
#include "report/advise.hpp"
#include "report/user_scene.hpp"
#include "verification/reference.hpp"
#include "verification/stability.hpp"

namespace stepwise {
namespace {

// a shipped PDE scene and the time its grid sets: h^2 / D (a diffusion's explicit limit scales with it), h / c (an
// advection's: the CFL number c dt / h)
struct ShippedPde {
  const char* scene;
  const char* unit;       // how the scale is written
  const char* parameter;  // D or c: the scale is h^2 / D or h / c
  bool diffusive;
  bool quick;             // in the quick report too
  double t_end = 0;       // the run's end, where not the scene's: Gray-Scott's patterns to t = 500 (its converged
                          // reference, two eighth-order runs at rtol 1e-13, then takes 2 s of the budget's half)
};
constexpr ShippedPde shipped[] = {
    {"heat-1d", "h²/D", "D", true, true},
    {"advection-upwind", "h/c", "c", false, false},
    {"fisher-kpp", "h²/D", "D", true, false},
};

// Gray-Scott (2 x 64^2 unknowns, to t = 500, the patterns' start), an explicit method against an implicit one:
// rk4 at 0.9 of its stable step (its error then far below any tolerance asked, its cost set by stability alone)
// against cvode-bdf at the loosest rtol of 1e-3, 1e-6, 1e-9 that meets rk4's error, each against the converged
// reference. A whole advice on it wants more than the report's budget (each of its 60 methods' sweeps runs 8192
// unknowns): `stepwise advise scenes/gray-scott.toml --t-end 500 --error 1e-4 --budget 120` gives it
constexpr double gray_scott_t_end = 500;
constexpr double explicit_share = 0.9;

struct CostRow {
  std::string method, setting;
  double error = NAN, cpu_seconds = NAN;
  long steps = 0, rhs_evals = 0;
};

std::vector<CostRow> gray_scott_costs(std::string& note) {
  RunOptions options;
  options.scene_file = scenes_directory() + "/gray-scott.toml";
  options.t_end = gray_scott_t_end;
  const PreparedRun p = prepare_run(options);
  const Model& model = *p.model;
  const Reference reference = converged_reference(model, gray_scott_t_end);
  note = fmt::format("against {} (their runs agree to {:.2g})", reference.methods, reference.agreement);
  const auto row = [&](const std::string& method, const StepControl& control, const std::string& setting) {
    const Measured m = run_and_measure(model, method, control, gray_scott_t_end, gray_scott_t_end);
    return CostRow{method, setting, m.result.status == Status::ok ? max_norm_error(m.result.y_stop, reference.y) : NAN, m.result.stats.cpu_seconds,
                   m.result.stats.steps, m.result.stats.rhs_evals};
  };
  std::vector<CostRow> rows;
  const double stable = *predicted_stable_dt(*find_method("rk4"), leading_spectrum(model, 0, model.initial_state()));
  const double dt = gray_scott_t_end / std::ceil(gray_scott_t_end / (explicit_share * stable));
  rows.push_back(row("rk4", StepControl::fixed(dt), fmt::format("dt {:.4g} (0.9 of its stable {:.4g})", dt, stable)));
  for (const int digits : {3, 6, 9}) {
    const double rtol = std::pow(10.0, -digits);
    rows.push_back(row("cvode-bdf", StepControl::adaptive(rtol, 1e-3 * rtol), fmt::format("rtol {:.0e}", rtol)));
    if (rows.back().error <= rows.front().error) break;
  }
  return rows;
}

// the explicit methods whose limits the table shows (every method's are in the CSV)
constexpr std::string_view shown_methods[] = {"euler", "rk4", "tsitouras54", "verner98"};

StudyOutput pde_scenes(const StudyContext& ctx) {
  // the quick report's budget is 2.5 s a scene, the full report's 6
  const double budget = ctx.quick ? 2.5 : 6, target = 1e-4;
  StudyOutput out;
  out.markdown = fmt::format(
      "The PDE scenes shipped in scenes/, written as text (docs/scenes.md, \"Your own PDE\"), asked what `stepwise advise` asks of a user's own "
      "(at an error of {:.0e} at t_end, within {:g} s each): each explicit method's largest stable step, predicted from the spectrum of the "
      "discretised operator's exact Jacobian at the start and its stability function, and found by bisection from the initial state; and the "
      "cheapest method, measured. The limits are given in the time the grid sets: h²/D where a diffusion bounds them (the explicit limit "
      "is a method's reach along the negative real axis times h²/(4D) in 1-D), h/c where an advection does (the CFL number). The spatial "
      "order the stencils reach is measured in the spatial-convergence section.\n\n",
      target, budget);
  Table limits{{"scene", "method", "unit", "unit_seconds", "predicted_stable_dt", "searched_stable_dt", "predicted_in_units", "searched_in_units",
                 "found_over_predicted"},
                {}};
  std::vector<Advice> advices;
  std::string verdicts;
  for (const ShippedPde& s : shipped) {
    if (ctx.quick && !s.quick) continue;
    RunOptions options;
    options.scene_file = scenes_directory() + "/" + s.scene + ".toml";
    if (s.t_end > 0) options.t_end = s.t_end;
    PreparedRun prepared;
    const StudyScene scene = user_study_scene(options, &prepared);
    const PdeGrid& grid = *pde_grid(*prepared.model);
    const double h = grid.x[1] - grid.x[0], value = prepared.params.at(s.parameter);
    const double unit = s.diffusive ? h * h / value : h / value;
    advices.push_back(advise(scene, target, budget, ctx.threads));
    const Advice& a = advices.back();
    for (const Candidate& c : a.candidates)
      if (c.predicted_stable_dt || c.searched_stable_dt) {
        const double predicted = c.predicted_stable_dt.value_or(NAN), searched = c.searched_stable_dt.value_or(NAN);
        limits.rows.push_back({a.scene, c.method, std::string(s.unit), unit, predicted, searched, predicted / unit, searched / unit, searched / predicted});
      }
    const Candidate* best = !a.candidates.empty() && a.candidates[0].cheapest ? &a.candidates[0] : nullptr;
    verdicts += best ? fmt::format("- **{}** ({} unknowns, stiffness {:.3g}): `{}` at {}, {:.3g} s of CPU for an error of {:.2e}.\n", a.scene,
                                   prepared.model->size(), a.stiffness, best->method, best->cheapest->setting(), best->cheapest->cpu_seconds,
                                   *best->cheapest->error)
                     : fmt::format("- **{}**: no method met {:.0e} within the budget.\n", a.scene, target);
  }
  out.markdown += "Predicted against found, for a few of the explicit methods (every method's in [pde_scene_limits.csv](pde_scene_limits.csv)):\n\n";
  out.markdown += markdown_table(limits,
                                 {{"scene", "scene"},
                                  {"method", "method"},
                                  {"unit", "unit"},
                                  {"predicted_in_units", "predicted dt (units)", shown_as("{:.3g}")},
                                  {"searched_in_units", "found dt (units)", shown_as("{:.3g}")},
                                  {"found_over_predicted", "found / predicted", shown_as("{:.3f}")}},
                                 [&](size_t r) {
                                   const auto& method = std::get<std::string>(cell_of(limits, limits.rows[r], "method"));
                                   return std::find(std::begin(shown_methods), std::end(shown_methods), method) != std::end(shown_methods);
                                 });
  out.markdown += "\nThe cheapest method for each, measured:\n\n" + verdicts + "\n";
  if (!ctx.quick) {
    std::string note;
    const std::vector<CostRow> costs = gray_scott_costs(note);
    Table cost{{"method", "setting", "error", "cpu_seconds", "steps", "rhs_evals"}, {}};
    for (const auto& r : costs) cost.rows.push_back({r.method, r.setting, r.error, r.cpu_seconds, r.steps, r.rhs_evals});
    out.markdown += fmt::format(
        "**Gray–Scott, explicit against implicit** (scenes/gray-scott.toml to t = {:g}, 2 × 64² unknowns; errors {}): rk4 at 0.9 of the "
        "stable step its stability function and the spectrum predict, and cvode-bdf (KLU on the exact sparse Jacobian) at the loosest "
        "tolerance meeting rk4's error.\n\n",
        gray_scott_t_end, note);
    out.markdown += markdown_table(cost, {{"method", "method"},
                                          {"setting", "setting"},
                                          {"error", "max error at t_end", shown_as("sci")},
                                          {"cpu_seconds", "CPU (s)", shown_as("{:.3g}")},
                                          {"steps", "steps"},
                                          {"rhs_evals", "calls of f"}});
    const CostRow &last = costs.back(), &first = costs.front();
    out.markdown += fmt::format("\nAt {} error the implicit method costs {:.2g} times the explicit one's CPU time: the spectrum calls the "
                                "system stiff (t_end times its fastest decay is past 1000), yet an implicit step's sparse factorisations on "
                                "8192 unknowns cost more than the explicit steps its larger steps save.\n\n",
                                last.error <= first.error ? "the same" : "a larger", last.cpu_seconds / first.cpu_seconds);
    if (last.error <= first.error)
      out.findings.push_back(fmt::format("**On a grid, stiff need not mean implicit**: on Gray–Scott (2 × 64² unknowns, to t = {:g}) rk4 at 0.9 of its "
                                         "predicted stable step reaches an error of {} in {:.3g} s of CPU, cvode-bdf the same error in {:.3g} s (PDE scenes).",
                                         gray_scott_t_end, sci(first.error), first.cpu_seconds, last.cpu_seconds));
    out.tables.emplace_back("pde_scene_gray_scott", std::move(cost));
  }
  for (const Advice& a : advices) out.figures.push_back(advice_figure(a, "pde_scene"));
  for (const Advice& a : advices)
    out.markdown += fmt::format("![{0}: error against CPU time, each method]({1}.png)\n\n", a.scene, out.figures[static_cast<size_t>(&a - advices.data())].stem());
  // the finding: the range of found / predicted over the explicit methods the table shows, on every scene
  double low = INFINITY, high = -INFINITY;
  for (const auto& row : limits.rows) {
    const auto& method = std::get<std::string>(cell_of(limits, row, "method"));
    const double ratio = std::get<double>(cell_of(limits, row, "found_over_predicted"));
    if (!std::isfinite(ratio) || std::find(std::begin(shown_methods), std::end(shown_methods), method) == std::end(shown_methods)) continue;
    low = std::min(low, ratio);
    high = std::max(high, ratio);
  }
  if (low <= high)
    out.findings.push_back(fmt::format("**A PDE's step limit, predicted**: on the shipped PDE scenes the largest stable step explicit Euler, rk4, "
                                       "tsitouras54 and verner98 are found to take by bisection is {:.3f} to {:.3f} times the one their stability "
                                       "functions and the grid's spectrum predict (PDE scenes).",
                                       low, high));
  AdviceTables tables = advice_tables(advices);
  for (auto& table : std::vector<std::pair<std::string, Table>>{{"pde_scene_limits", std::move(limits)}, {"pde_scene_summary", std::move(tables.summary)},
                                                                {"pde_scene_candidates", std::move(tables.candidates)}, {"pde_scene_sweep", std::move(tables.sweep)}})
    out.tables.push_back(std::move(table));
  return out;
}

}  // namespace

Study pde_scenes_study() { return {"pde-scenes", "Your own PDE: the shipped scenes' step limits and cheapest methods", pde_scenes}; }

}  // namespace stepwise
