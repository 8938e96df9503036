// The report's study: work-precision: error against cost for every method, the Pareto fronts, the recommendations.
#include "report/cost_model.hpp"
#include "report/studies/study_scenes.hpp"

#include <optional>

namespace stepwise {
namespace {

// a fixed-step point expected to take longer than this (CPU ns, report/cost_model) is left out: a fixed-step
// method's finest points cost the most and say the least (a slow method's error at a step nobody would pay for;
// gpu-cloth's float32 errors grow as dt falls, the shear layer's ark324 reaches round-off long before), and the
// report is promised in 10 minutes on 2 cores (1 minute quick). Fixed-step points only: their steps are known,
// while an adaptive implicit one's are estimated from rtol alone, up to 10x high on the sheet
// The quick report, a preview, keeps the points its recommendations are read from (milliseconds each; its finest
// points of a second or two on the sheet decide nothing)
constexpr double point_budget_ns = 3e9, quick_point_budget_ns = 1e8;

// what a point measured (the plan says what it ran)
struct Outcome {
  std::optional<double> error;
  double rhs_evals = 0, cpu_seconds = 0;
  long steps = 0;
  Status status = Status::ok;
  static auto fields(auto& s) { return std::tie(s.error, s.rhs_evals, s.cpu_seconds, s.steps, s.status); }
};

// one point of a work-precision sweep
struct WorkPoint {
  const StudyScene* scene = nullptr;
  const Method* method = nullptr;
  StepControl control;
  std::optional<double> error;  // empty: failed or diverged
  double rhs_evals = 0, cpu_seconds = 0;
  long steps = 0;
  Status status = Status::ok;
  bool coarsest = false;  // the method's coarsest point in the sweep: a coarser one might have met the target too

  std::string setting() const { return control.dt ? fmt::format("dt {:.3g}", *control.dt) : fmt::format("rtol {:.0e}", control.rtol); }
};

// the points no other point beats in both cost and error: sorted by cost, each more accurate than every cheaper one
std::vector<const WorkPoint*> pareto_front(const std::vector<const WorkPoint*>& points, double WorkPoint::*cost) {
  std::vector<const WorkPoint*> ok;
  for (const WorkPoint* p : points)
    if (p->error) ok.push_back(p);
  std::stable_sort(ok.begin(), ok.end(), [&](const WorkPoint* a, const WorkPoint* b) {
    return a->*cost < b->*cost || (a->*cost == b->*cost && *a->error < *b->error);
  });
  std::vector<const WorkPoint*> front;
  for (const WorkPoint* p : ok)
    if (front.empty() || *p->error < *front.back()->error) front.push_back(p);
  return front;
}

// the cheapest point of a front reaching the target: the first on it at or below the target
const WorkPoint* cheapest_reaching(const std::vector<const WorkPoint*>& front, double target) {
  for (const WorkPoint* p : front)
    if (*p->error <= target) return p;
  return nullptr;
}

// a point's expected CPU time in nanoseconds (report/cost_model.hpp), the runs repeated when short
double expected_cost(const WorkPoint& p, double n, int repeats) {
  const double once = expected_run_ns(*p.method, p.control, p.scene->t_end, p.scene->time_scale, n);
  return once < short_run_seconds * 1e9 ? once * (1 + repeats) : once;
}

// the reference states of the scenes without an exact solution (a user's scene's checked by two methods), and
// what the section says of them
std::map<const StudyScene*, Eigen::VectorXd> reference_states(const std::vector<StudyScene>& scenes, std::string& note) {
  std::map<const StudyScene*, Eigen::VectorXd> reference;
  for (const auto& scene : scenes)
    if (const auto model = scene_model(scene); !model->has_exact() && scene.factory) {
      const Reference r = converged_reference(*model, scene.t_end);
      reference[&scene] = r.y;
      note += fmt::format("{} has no exact solution: its errors are against {}, which agree to {:.2e}. ", scene.label, r.methods, r.agreement);
    } else if (!model->has_exact()) {
      const Measured m = run_and_measure(*model, reference_method, StepControl::adaptive(reference_rtol, 1e-3 * reference_rtol), scene.t_end, scene.t_end);
      if (m.result.status != Status::ok)
        throw std::runtime_error(fmt::format("work-precision: the reference run of {} ({}) failed: {}", scene.label, reference_method, m.result.message));
      reference[&scene] = m.result.y_stop;
    }
  return reference;
}

// the sweep's points: every method of every scene, fixed-step ones over `halvings` halvings of their coarsest
// step, adaptive ones over `rtols` down to their order's floor; those expected to cost over the budget left out
std::vector<WorkPoint> work_plan(const StudyContext& ctx, const std::vector<StudyScene>& scenes, int halvings, const std::vector<double>& rtols,
                                 const std::map<const StudyScene*, double>& sizes, int repeats) {
  std::vector<WorkPoint> plan;
  for (const auto& scene : scenes)
    for (const Method* method : scene_methods(scene, false)) {
      WorkPoint point{&scene, method, {}, {}, 0, 0, 0, Status::ok, false};
      if (method->fixed_step())
        for (int k = 0; k <= halvings; ++k) {
          const double coarse = solves_newton_systems(*method) && scene.implicit_dt > 0 ? scene.implicit_dt : coarse_dt(*method, scene.time_scale);
          point.control = StepControl::fixed(coarse / std::pow(2.0, k));
          point.coarsest = k == 0;
          plan.push_back(point);
        }
      if (method->adaptive())
        for (const double rtol : rtols) {
          // an order-p method's steps grow as rtol^(-1/(p+1)): past 10^-(2+2p) a low-order one takes 1e5 and
          // more steps for errors the higher orders reach in hundreds, and the point only says it is too slow.
          // The quick report stops a decade sooner, at 10^-(2p), and at the verification target's 1e-8 at most
          // (1e-4 for a method solving Newton systems, whose points at 1e-6 took 1-2 s on the sheet): its
          // recommendations are read at errors the explicit methods reach well before
          const int floor_exponent = ctx.quick ? std::min(2 * method->order.max, solves_newton_systems(*method) ? 4 : 8) : 2 + 2 * method->order.max;
          if (rtol < std::pow(10.0, -floor_exponent) * (1 - 1e-9)) continue;
          point.control = StepControl::adaptive(rtol, 1e-3 * rtol);
          point.coarsest = rtol == rtols.front();
          // a low-order method at a tight tolerance needs millions of steps: such a point is reported as failed
          // past this budget rather than allowed to stall the report
          point.control.max_steps = 200'000;
          plan.push_back(point);
        }
    }
  const double budget_ns = ctx.quick ? quick_point_budget_ns : point_budget_ns;
  std::erase_if(plan, [&](const WorkPoint& p) { return p.control.dt && expected_cost(p, sizes.at(p.scene), repeats) > budget_ns; });
  return plan;
}

// the plan's points run (least_of_runs), each with its error against the exact solution or the reference
std::vector<WorkPoint> run_plan(const StudyContext& ctx, const std::vector<WorkPoint>& plan, const std::map<const StudyScene*, double>& sizes, int repeats,
                                const std::map<const StudyScene*, Eigen::VectorXd>& reference) {
  std::vector<std::string> labels;
  std::vector<double> costs;
  std::vector<std::string> groups;  // one method on one scene
  for (const auto& p : plan) {
    labels.push_back(fmt::format("{} {} {}", p.scene->label, p.method->name, p.setting()));
    costs.push_back(expected_cost(p, sizes.at(p.scene), repeats));
    groups.push_back(fmt::format("{} {}", p.scene->label, p.method->name));
  }
  const auto outcomes = ctx.sweep<Outcome>(labels, [&](size_t i) {
    const WorkPoint& p = plan[i];
    const auto model = scene_model(*p.scene);
    const Measured m = least_of_runs(*model, p.method->name, p.control, p.scene->t_end, 1 + repeats);
    Outcome o{m.error, static_cast<double>(m.result.stats.rhs_evals), m.result.stats.cpu_seconds, m.result.stats.steps, m.result.status};
    if (!model->has_exact() && m.result.status == Status::ok) o.error = max_norm_error(m.result.y_stop, reference.at(p.scene));
    return o;
  }, costs, groups);
  std::vector<WorkPoint> runs = plan;
  for (size_t i = 0; i < runs.size(); ++i) {
    const Outcome& o = outcomes[i];
    runs[i].error = o.error;
    runs[i].rhs_evals = o.rhs_evals;
    runs[i].cpu_seconds = o.cpu_seconds;
    runs[i].steps = o.steps;
    runs[i].status = o.status;
  }
  return runs;
}

// a scene's recommendations: for each purpose's target, the cheapest point on the CPU front meeting it and the
// cheapest point of any other method meeting it (the runner-up)
void add_recommendations(const StudyScene& scene, const std::vector<const WorkPoint*>& mine, const std::vector<const WorkPoint*>& by_cpu, Table& advice) {
  for (const auto& [purpose, target] : {std::pair<std::string, double>{"animation", 0.5 * scene.frame_extent / frame_pixels}, {"verification", verification_target}}) {
    const WorkPoint* best = cheapest_reaching(by_cpu, target);
    if (!best) {
      advice.rows.push_back({scene.label, scene.frame_extent, purpose, target, std::string("none"), std::string(), 0L, NAN, NAN, NAN, std::string("none"), NAN, NAN});
      continue;
    }
    const WorkPoint* runner = nullptr;
    for (const WorkPoint* p : mine)
      if (p->error && *p->error <= target && p->method != best->method && (!runner || p->cpu_seconds < runner->cpu_seconds)) runner = p;
    const std::string runner_name = runner ? fmt::format("{} ({})", runner->method->name, runner->setting()) : "none";
    const double runner_cpu = runner ? runner->cpu_seconds : NAN;
    advice.rows.push_back({scene.label, scene.frame_extent, purpose, target, std::string(best->method->name), best->setting(),
                           static_cast<long>(best->coarsest), *best->error, best->cpu_seconds, best->rhs_evals, runner_name, runner_cpu, runner_cpu / best->cpu_seconds});
  }
}

// a scene's subsection: its work-precision figure (each cost's panel: the sweep, and behind it the front,
// work_precision_pareto.csv) and its Pareto front in CPU time
std::string scene_section(const StudyScene& scene, const Table& fronts, std::vector<Figure>& figures) {
  const auto against = [&](std::string cost, std::string label, std::string title) {
    FigureSpec::Panel panel{.title = fmt::format("{}: {}", scene.label, title), .x_label = std::move(label), .y_label = "max-norm error at t_end",
                            .log_x = true, .log_y = true,
                            .layers = {{.table = "work_precision_pareto", .x = cost, .y = "error", .label = "Pareto front", .mark = FigureMark::front,
                                        .where = {{"scene", {scene.label}}, {"cost", {cost}}}, .hover = {{"method", "method"}, {"setting", "setting"}}}}};
    for (auto& layer : by_mode({.table = "work_precision", .x = cost, .y = "error", .where = {{"scene", {scene.label}}}})) panel.layers.push_back(std::move(layer));
    return panel;
  };
  FigureSpec spec{.title = "Work against precision, " + scene.label,
                  .panels = {against("cpu_seconds", "CPU time (s)", "error against CPU time (dashed: adaptive; x: failed)"),
                             against("rhs_evals", "right-hand-side evaluations", "error against evaluations")}};
  std::string section = fmt::format("### {}\n\n{}Pareto front in CPU time (no other point is both cheaper and more accurate):\n\n", scene.label,
                                    add_figure(figures, "work_precision", scene.label, std::move(spec), "Work-precision diagram, " + scene.label));
  section += markdown_table(fronts,
                            {{"cpu_seconds", "CPU (s)", shown_as("{:.2e}")},
                             {"error", "error", shown_as("{:.2e}")},
                             {"method", "method"},
                             {"setting", "setting"}},
                            [&](size_t row) {
                              return std::get<std::string>(cell_of(fronts, fronts.rows[row], "scene")) == scene.label &&
                                     std::get<std::string>(cell_of(fronts, fronts.rows[row], "cost")) == "cpu_seconds";
                            });
  return section + "\n";
}

// whether a recommendation row found a method (a target no method reached leaves the row's other cells empty)
bool reached(const Table& advice, const std::vector<Cell>& row) { return std::get<std::string>(cell_of(advice, row, "method")) != "none"; }

// the recommendations' Markdown table
std::string recommendations_table(const Table& advice) {
  const auto if_reached = [&](std::string column, std::string spec) {
    return [&, column, spec](const std::vector<Cell>& row) { return reached(advice, row) ? shown_as(spec)(cell_of(advice, row, column)) : std::string(); };
  };
  return markdown_table(
      advice, {{"", "scene", {},
                [&](const std::vector<Cell>& row) {
                  const std::string& label = std::get<std::string>(cell_of(advice, row, "scene"));
                  return reached(advice, row) ? fmt::format("{} ({:g} m frame)", label, std::get<double>(cell_of(advice, row, "frame_m"))) : label;
                }},
               {"purpose", "purpose"},
               {"target", "target", shown_as("{:.1e}")},
               {"", "method", {},
                [&](const std::vector<Cell>& row) { return reached(advice, row) ? std::get<std::string>(cell_of(advice, row, "method")) : "none reached it"; }},
               {"", "setting", {},
                [&](const std::vector<Cell>& row) {
                  if (!reached(advice, row)) return std::string();
                  return std::get<std::string>(cell_of(advice, row, "setting")) + (std::get<long>(cell_of(advice, row, "coarsest_swept")) ? " *" : "");
                }},
               {"", "error", {}, if_reached("error", "{:.1e}")},
               {"", "CPU (s)", {}, if_reached("cpu_seconds", "{:.1e}")},
               {"", "runner-up", {}, if_reached("runner_up", "{}")},
               {"", "its CPU / the best's", {}, if_reached("runner_up_over_best", "{:.1f}")}});
}

// the finding: which methods the recommendations name, and how much the runner-up costs at most; empty if none
std::optional<std::string> recommendations_finding(const Table& advice) {
  std::map<std::string, int> named;
  int met = 0;
  double worst_runner = 0;
  for (const auto& row : advice.rows) {
    if (!reached(advice, row)) continue;
    ++met;
    ++named[std::get<std::string>(cell_of(advice, row, "method"))];
    if (const double r = std::get<double>(cell_of(advice, row, "runner_up_over_best")); std::isfinite(r)) worst_runner = std::max(worst_runner, r);
  }
  if (met == 0) return std::nullopt;
  std::vector<std::pair<int, std::string>> ranked;
  for (const auto& [method, count] : named) ranked.emplace_back(-count, method);
  std::sort(ranked.begin(), ranked.end());
  std::string list;
  int listed = 0;
  for (size_t i = 0; i < ranked.size() && i < 3; ++i) {
    list += fmt::format("{}`{}` in {}", i ? ", " : "", ranked[i].second, -ranked[i].first);
    listed -= ranked[i].first;
  }
  if (ranked.size() > 3) list += fmt::format(", {} other methods in {}", ranked.size() - 3, met - listed);
  return fmt::format("**The cheapest method for the accuracy a scene needs**, measured on {} scene targets (half a pixel, "
                     "and {:.0e} for verification): {}; the next-best other method costs up to {:.1f} times as much.",
                     met, verification_target, list, worst_runner);
}

StudyOutput work_precision(const StudyContext& ctx) {
  const int repeats = ctx.quick ? 1 : 3;
  const int halvings = ctx.quick ? 3 : 7;
  std::vector<double> rtols;
  for (int e = 2; e <= 12; e += ctx.quick ? 2 : 1) rtols.push_back(std::pow(10.0, -e));

  const auto scenes = scenes_or(ctx, work_precision_scenes(ctx.quick));
  std::string reference_note;
  const auto reference = reference_states(scenes, reference_note);
  std::map<const StudyScene*, double> sizes;  // each scene's state size, for the cost model
  for (const auto& scene : scenes) sizes[&scene] = scene_model(scene)->size();
  const std::vector<WorkPoint> runs = run_plan(ctx, work_plan(ctx, scenes, halvings, rtols, sizes, repeats), sizes, repeats, reference);

  Table points{{"scene", "method", "mode", "dt", "rtol", "error", "rhs_evals", "steps", "cpu_seconds", "status"}, {}};
  Table fronts{{"scene", "cost", "method", "setting", "error", "rhs_evals", "cpu_seconds"}, {}};
  Table advice{{"scene", "frame_m", "purpose", "target", "method", "setting", "coarsest_swept", "error", "cpu_seconds", "rhs_evals", "runner_up",
                "runner_up_cpu_seconds", "runner_up_over_best"},
               {}};
  for (const auto& p : runs)
    points.rows.push_back({p.scene->label, std::string(p.method->name), std::string(p.control.dt ? "fixed" : "adaptive"),
                           p.control.dt.value_or(NAN), p.control.dt ? NAN : p.control.rtol, p.error.value_or(NAN), p.rhs_evals, p.steps,
                           p.cpu_seconds, std::string(to_string(p.status))});

  StudyOutput out;
  std::string sections;
  for (const auto& scene : scenes) {
    std::vector<const WorkPoint*> mine;
    for (const auto& p : runs)
      if (p.scene == &scene) mine.push_back(&p);
    const auto by_cpu = pareto_front(mine, &WorkPoint::cpu_seconds);
    const auto by_rhs = pareto_front(mine, &WorkPoint::rhs_evals);
    for (const auto& [cost, front] : {std::pair{"cpu_seconds", &by_cpu}, {"rhs_evals", &by_rhs}})
      for (const WorkPoint* p : *front)
        fronts.rows.push_back({scene.label, std::string(cost), std::string(p->method->name), p->setting(), *p->error, p->rhs_evals, p->cpu_seconds});
    add_recommendations(scene, mine, by_cpu, advice);
    sections += scene_section(scene, fronts, out.figures);
  }
  const double budget_ns = ctx.quick ? quick_point_budget_ns : point_budget_ns;
  out.markdown =
      fmt::format("### Recommendations\n\nPer scene, the cheapest method in CPU time that meets each target, read off the Pareto front "
                  "below: for animation, half a pixel of a {:.0f}-pixel-high frame showing the scene (the frame's height in metres is given; "
                  "the target applies to the state's max-norm error, velocities included, so it errs strict), and for verification "
                  "{:.0e}. The runner-up is the cheapest other method meeting the same target, with its cost as a ratio. A setting marked * is "
                  "the coarsest its method was swept at: a coarser one might meet the target for less.\n\n",
                  frame_pixels, verification_target) +
      recommendations_table(advice) + "\n" + reference_note +
      fmt::format("Error at t_end (max norm against the exact solution; for the cloth, against {} at rtol {:.0e}) against cost.", reference_method, reference_rtol) +
      fmt::format(" Fixed-step methods are swept over {} dt halvings, adaptive ones over rtol (atol = 1e-3 rtol) from 1e-2 to 1e-12 "
                  "{}-fold apart (an order-p method down to 10^-({}2p)), leaving out the fixed-step points expected to take over {:g} s of CPU. ",
                  halvings, ctx.quick ? 100 : 10, ctx.quick ? "" : "2 + ", budget_ns * 1e-9) +
      "CPU time is the minimum over repeated runs after a discarded warm-up (a run over 0.2 s is timed once). "
      "Failed or diverged points are drawn as crosses at the top of each diagram and stay in the CSV with their status. "
      "The GPU methods (`gpu-wave`, `gpu-symplectic-euler`, `gpu-cloth`) run their passes on llvmpipe in the calling thread, so "
      "their CPU time is their whole cost: a pass and a read-back per step, which on these small grids costs more than the "
      "CPU's step. They compute in float32, which sets a floor: `gpu-wave`'s is its rounded coefficients (the convergence "
      "section), and on the 6 x 6 sheet `gpu-cloth`'s error rises as dt falls, since an increment h v below u |x| "
      "(u = 6e-8) is rounded away and the roundings pile up over more steps: float32 explicit cloth wants steps near its "
      "stability limit.\n\n" +
      std::string(dense_note) + sections;
  if (auto finding = recommendations_finding(advice)) out.findings.push_back(std::move(*finding));
  out.tables = {{"work_precision", std::move(points)}, {"work_precision_pareto", std::move(fronts)}, {"recommendations", std::move(advice)}};
  return out;
}

}  // namespace

Study work_precision_study() { return {.name = "work-precision", .title = "Accuracy against cost, and the recommendations", .run = work_precision, .scene_problem = [](const StudyScene&, const Model&) { return std::string(); }}; }

}  // namespace stepwise
