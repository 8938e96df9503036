// The report's study: convergence: error against dt for every fixed-step method, with the fitted order.
#include "report/cost_model.hpp"
#include "report/studies/study_scenes.hpp"

namespace stepwise {
namespace {

StudyOutput convergence(const StudyContext& ctx) {
  const int halvings = ctx.quick ? 4 : 6;
  Table points{{"scene", "method", "dt", "steps", "rhs_evals", "error", "status"}, {}};
  Table orders{{"scene", "method", "documented_order", "observed_order", "coarsest_error", "finest_error"}, {}};
  StudyOutput out;
  out.markdown = "Observed order: least-squares slope of log(error at t_end) against log(dt) over the halvings, fitted to "
                 "the errors between 1e-12 (round-off) and 1e-1 (pre-asymptotic), against the order of the method table. "
                 "GSL's multistep and extrapolation steppers (bsimp, msadams, msbdf) choose their order from the error "
                 "control, so their slope is only reported (nan: every error at round-off). `gpu-wave` computes in float32 "
                 "(the seeds' scheme as a fragment shader): its coefficients, rounded to float, misplace each mode's angle "
                 "theta by about u / theta^2 relatively, u = 6e-8, which grows fourfold per halving of dt, so its error stops "
                 "falling near 1e-3 on the standing wave and then rises: its slope measures float32, not the scheme. "
                 "`gpu-symplectic-euler`, also float32, keeps its order: carrying v instead of z^{k-1} adds a small "
                 "increment to z each step instead of taking the difference of two nearly equal levels. `stable-fluids` on the "
                 "Taylor-Green vortex keeps the error of its grid, whatever its step (bilinear interpolation's diffusion, about "
                 "d^2 / h, even grows as h shrinks): its slope in dt is flat, and its order at a fixed CFL number is the fluid "
                 "section's.\n\n" +
                 std::string(dense_note);

  // one point per (scene, method): its whole sweep of halvings, which the fit needs together
  struct Point {
    const StudyScene* scene;
    const Method* method;
  };
  const auto scenes = scenes_or(ctx, ode_scenes());
  // a user's scene without an exact solution: errors against the converged reference (verification/reference.hpp)
  std::map<const StudyScene*, Reference> references;
  for (const auto& scene : scenes)
    if (const auto model = scene_model(scene); !model->has_exact()) {
      references.emplace(&scene, converged_reference(*model, scene.t_end));
      out.markdown += fmt::format("{} has no exact solution: its errors are against {}, which agree to {:.2e}.\n\n", scene.label,
                                  references.at(&scene).methods, references.at(&scene).agreement);
    }
  std::vector<Point> plan;
  std::vector<std::string> labels;
  // each point's expected cost (report/cost_model.hpp): its runs at the coarse step and each halving of it
  // (grouped by scene: the time-left estimate learns each scene's ratio of seconds to expected cost on its own)
  std::vector<double> costs;
  std::vector<std::string> groups;
  for (const auto& scene : scenes) {
    const double n = scene_model(scene)->size();
    for (const Method* method : scene_methods(scene, true)) {
      plan.push_back({&scene, method});
      labels.push_back(fmt::format("{} {}", scene.label, method->name));
      double cost = 0;
      for (const double dt : convergence_steps(*method, halvings, coarse_dt(*method, scene.time_scale)))
        cost += expected_run_ns(*method, StepControl::fixed(dt), scene.t_end, scene.time_scale, n);
      costs.push_back(cost);
      groups.push_back(scene.label);
    }
  }
  const auto sweeps = ctx.sweep<ConvergenceSweep>(labels, [&](size_t i) {
    const auto model = scene_model(*plan[i].scene);
    const auto reference = references.find(plan[i].scene);
    return convergence_sweep(*model, *plan[i].method, plan[i].scene->t_end, halvings, coarse_dt(*plan[i].method, plan[i].scene->time_scale),
                             reference == references.end() ? nullptr : &reference->second.y);
  }, costs, groups);

  std::vector<const StudyScene*> shown;  // the scenes in the plan's order
  for (size_t i = 0; i < plan.size(); ++i) {
    const auto& [scene, method] = plan[i];
    const ConvergenceSweep& sweep = sweeps[i];
    if (shown.empty() || shown.back() != scene) shown.push_back(scene);
    for (size_t k = 0; k < sweep.runs.size(); ++k) {
      const Measured& m = sweep.runs[k];
      points.rows.push_back({scene->label, std::string(method->name), sweep.dt[k], m.result.stats.steps, m.result.stats.rhs_evals,
                             m.error.value_or(std::numeric_limits<double>::quiet_NaN()), std::string(to_string(m.result.status))});
    }
    // errors of the coarsest and finest runs that succeeded, whether or not they entered the fit
    std::vector<double> errors;
    for (const auto& m : sweep.runs)
      if (m.error) errors.push_back(*m.error);
    const double coarsest = errors.empty() ? NAN : errors.front(), finest = errors.empty() ? NAN : errors.back();
    orders.rows.push_back({scene->label, std::string(method->name), std::string(method->order.text), sweep.observed_order, coarsest, finest});
  }
  // a section per scene: its figure, and its rows of the orders' table
  for (size_t s = 0; s < shown.size(); ++s) {
    const std::string& label = shown[s]->label;
    if (s > 0) out.markdown += "\n";
    // each method's legend entry: its observed slope against its documented order
    std::map<std::string, std::string> names;
    for (const auto& row : orders.rows)
      if (std::get<std::string>(cell_of(orders, row, "scene")) == label) {
        const std::string method = std::get<std::string>(cell_of(orders, row, "method"));
        names[method] = fmt::format("{}: {:.2f} (order {})", method, std::get<double>(cell_of(orders, row, "observed_order")),
                                    std::get<std::string>(cell_of(orders, row, "documented_order")));
      }
    FigureSpec spec{.title = fmt::format("{}: convergence (legend: observed slope, documented order; x: diverged or failed)", label),
                    .panels = {{.x_label = "step dt (s)", .y_label = "max-norm error at t_end", .log_x = true, .log_y = true,
                                .layers = {{.table = "convergence", .x = "dt", .y = "error", .series = "method", .where = {{"scene", {label}}},
                                            .failures = true, .hover = {{"steps", "steps"}, {"rhs_evals", "calls of f"}}, .names = std::move(names)}}}}};
    out.markdown += fmt::format("### {}\n\n{}", label, add_figure(out.figures, "convergence", label, std::move(spec), "Error at t_end against dt, " + label));
    out.markdown += markdown_table(orders,
                                   {{"method", "method"},
                                    {"documented_order", "order (method table)"},
                                    {"observed_order", "observed order", shown_as("{:.2f}")},
                                    {"coarsest_error", "error at coarsest dt", shown_as("sci")},
                                    {"finest_error", "error at finest dt", shown_as("sci")}},
                                   [&](size_t row) { return std::get<std::string>(orders.rows[row][0]) == label; });
  }
  out.markdown += "\n";
  out.tables = {{"convergence", std::move(points)}, {"convergence_orders", std::move(orders)}};
  return out;
}

}  // namespace

Study convergence_study() { return {.name = "convergence", .title = "Convergence", .run = convergence, .scene_problem = [](const StudyScene&, const Model&) { return std::string(); }}; }

}  // namespace stepwise
