// The report's study: contacts: a tumbling box, resting and sliding on slopes, and the collapsing wall, by step.
#include "report/studies.hpp"

#include "models/bouncing_ball.hpp"
#include "models/model.hpp"
#include "models/pendulum.hpp"
#include "models/rigid_body.hpp"
#include "solvers/capabilities/mass_spring.hpp"
#include "solvers/capabilities/second_order.hpp"
#include "solvers/wave_step.hpp"
#include "verification/adequacy.hpp"
#include "verification/contact_checks.hpp"
#include "verification/convergence.hpp"
#include "verification/invariants.hpp"
#include "run/measure.hpp"
#include "verification/stability.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

namespace stepwise {
namespace {

// one step size's measurements of the two scenes
struct Row {
  size_t tumble_impacts = 0, collapse_impacts = 0;
  double rest = 0, sink = 0, creep = 0, slide_error = 0, rate = 0, kept = 0;
  bool ok = false;
  static auto fields(auto& s) {
    return std::tie(s.tumble_impacts, s.collapse_impacts, s.rest, s.sink, s.creep, s.slide_error, s.rate, s.kept, s.ok);
  }
};

StudyOutput contacts(const StudyContext& ctx) {
  const bool quick = ctx.quick;
  // per step: the tumbling box (the model's defaults, the scene's drop), a box resting on a slope inside its friction cone and
  // one sliding down a steeper slope (Coulomb's acceleration exact), and the collapsing wall
  const double rest_time = quick ? 2 : 10, collapse_time = quick ? 1 : 3;
  const double hz = resolve_params(*find_model("dropped-body"), {}).at("hz");  // the resting height on the largest face
  const double steep = std::atan(0.75), gentle = std::atan(0.25), mu = 0.5;
  const double coulomb = 9.81 * (std::sin(steep) - mu * std::cos(steep));
  Table table{{"dt", "tumble_impacts", "tumble_rest_time", "tumble_sink", "slope_creep", "slide_error", "collapse_steps_per_second",
               "collapse_impacts", "collapse_energy_kept", "status"},
              {}};
  std::string md = fmt::format(
      "Rigid bodies in contact, stepped by `sequential-impulses` at each dt. The tumbling box (the scene's drop from 1.5 m with a spin): "
      "impacts, when it comes to rest (kinetic energy below 1e-9 of its start for good) and how far below its resting height hz it "
      "ends. A box on a slope of tan 0.25 (mu = 0.5): the largest move along the ground over {:.0f} s after 50 ms. A box on a slope of "
      "tan 0.75: its speed after 1 s against Coulomb's g (sin s - mu cos s) t, relative. The wall hit by the ball over {:.0f} s: steps "
      "per CPU second, impacts, and the fraction of the energy left.\n\n",
      rest_time, collapse_time);
  double worst_creep = 0, worst_slide = 0, fewest_kept = 1, most_kept = 0;
  std::pair<size_t, size_t> impacts{std::numeric_limits<size_t>::max(), 0};
  const std::vector<double> dts{4e-3, 2e-3, 1e-3, 5e-4};
  std::vector<std::string> labels;
  // a point's cost goes as its steps, 1 / dt (no nanoseconds: the sweep learns the scale from its first point)
  std::vector<double> costs;
  for (const double dt : dts) {
    labels.push_back(fmt::format("dt {:g}", dt));
    costs.push_back(1 / dt);
  }
  const auto rows = ctx.sweep<Row>(labels, [&](size_t i) {
    Row row;
    const StepControl control = StepControl::fixed(dts[i]);
    const auto box = make_model("dropped-body");  // its defaults are the scene's drop
    const Measured t = run_and_measure(*box, "sequential-impulses", control, 5.0, 0.01);
    const auto names = box->summary_names();
    const auto kinetic_at = std::find(names.begin(), names.end(), "kinetic") - names.begin();
    const double k0 = box->summary(box->initial_state())[kinetic_at];
    for (size_t k = 0; k < t.result.trajectory.y.size(); ++k)
      if (box->summary(t.result.trajectory.y[k])[kinetic_at] > 1e-9 * k0) row.rest = t.result.trajectory.t[k];
    row.tumble_impacts = t.result.events.size();
    row.sink = hz - t.result.y_stop[2];
    const auto gentle_box = make_model("dropped-body", box_on_slope(gentle, mu));
    row.creep = slope_motion(run_and_measure(*gentle_box, "sequential-impulses", control, rest_time, 0.01).result, gentle, 0.05).creep;
    const auto steep_box = make_model("dropped-body", box_on_slope(steep, mu));
    const SlopeMotion slid = slope_motion(run_and_measure(*steep_box, "sequential-impulses", control, 1.0, 0.1).result, steep, 0.05);
    row.slide_error = std::abs(slid.speed / coulomb - 1);
    const auto wall = make_model("box-stack");
    const RunResult c = make_integrator("sequential-impulses", control)->integrate(*wall, 0, wall->initial_state(), std::vector<double>{collapse_time});
    row.kept = *wall->energy(c.y_stop) / *wall->energy(wall->initial_state());
    row.rate = static_cast<double>(c.stats.steps) / c.stats.cpu_seconds;
    row.collapse_impacts = c.events.size();
    row.ok = t.result.status == Status::ok && c.status == Status::ok;
    return row;
  }, costs);
  for (size_t i = 0; i < dts.size(); ++i) {
    const Row& r = rows[i];
    table.rows.push_back({dts[i], static_cast<double>(r.tumble_impacts), r.rest, r.sink, r.creep, r.slide_error, r.rate,
                          static_cast<double>(r.collapse_impacts), r.kept, std::string(r.ok ? "ok" : "failed")});
    worst_creep = std::max(worst_creep, r.creep);
    worst_slide = std::max(worst_slide, r.slide_error);
    fewest_kept = std::min(fewest_kept, r.kept);
    most_kept = std::max(most_kept, r.kept);
    impacts = {std::min(impacts.first, r.collapse_impacts), std::max(impacts.second, r.collapse_impacts)};
  }
  md += markdown_table(table, {{"dt", "dt (s)", shown_as("{:g}")},
                               {"tumble_impacts", "tumble: impacts", shown_as("{:g}")},
                               {"tumble_rest_time", "at rest (s)", shown_as("{:.2f}")},
                               {"tumble_sink", "below hz (m)", shown_as("sci")},
                               {"slope_creep", "slope creep (m)", shown_as("sci")},
                               {"slide_error", "slide error", shown_as("sci")},
                               {"collapse_steps_per_second", "collapse: steps/s", shown_as("{:.0f}")},
                               {"collapse_impacts", "impacts", shown_as("{:g}")},
                               {"collapse_energy_kept", "energy kept", shown_as("{:.3f}")}});
  md += fmt::format(
      "\n- Over every dt the resting box moved at most {} m along the slope and the sliding box's speed was within {} of "
      "Coulomb's: velocity-level contact holds both exactly at any step, to round-off.\n"
      "- The collapse is chaotic: from dt to dt its impacts range over {}-{} and the energy it keeps over {:.3f}-{:.3f}, though "
      "a run repeated is bit-identical. The bounce changes with the step too (a step resolves one approach at a time).\n\n",
      sci(worst_creep), sci(worst_slide), impacts.first, impacts.second, fewest_kept, most_kept);
  std::vector<Figure> figures;
  const auto against_dt = [](std::string column, std::string label, double floor) {
    return FigureSpec::Layer{.table = "contacts", .x = "dt", .y = std::move(column), .label = std::move(label), .floor = floor};
  };
  FigureSpec spec{.title = "Contacts against the step",
                  .panels = {{.title = "Resting and sliding contact (an exact 0 drawn at 1e-20)", .x_label = "step dt (s)", .y_label = "error",
                              .log_x = true, .log_y = true,
                              .layers = {against_dt("tumble_sink", "tumbling box: final depth below its resting height (m)", 0),
                                         against_dt("slope_creep", "box at rest on a slope: creep (m)", 1e-20),
                                         against_dt("slide_error", "box sliding: speed against Coulomb's, relative", 1e-20)}},
                             {.title = "The wall's collapse: chaotic, so it changes with the step", .x_label = "step dt (s)",
                              .y_label = "fraction of the energy kept", .log_x = true, .layers = {against_dt("collapse_energy_kept", "energy kept", 0)}},
                             {.title = "The wall's collapse: impacts", .x_label = "step dt (s)", .y_label = "impacts", .log_x = true,
                              .layers = {against_dt("collapse_impacts", "impacts", 0)}}}};
  md += add_figure(figures, "contacts", "", std::move(spec), "Contacts against the step: the resting box's sink and the slopes' errors, and the collapse's energy and impacts");
  return {{{"contacts", std::move(table)}}, md, figures};
}

}  // namespace

Study contacts_study() { return {"contacts", "Contacts: a tumbling box, resting and sliding on slopes, and the collapsing wall, by step", contacts}; }

}  // namespace stepwise
