// The studies of accuracy against step and cost on the scenes with exact solutions: convergence, work-precision
// (with its Pareto fronts and the recommendations drawn from them), and the methods' stability regions against
// the scenes' spectra.
#include "studies.hpp"

#include "models/model.hpp"
#include "solvers/capabilities/mass_spring.hpp"
#include "solvers/wave_step.hpp"
#include "verification/convergence.hpp"
#include "run/measure.hpp"
#include "verification/stability.hpp"
#include "verification/tolerances.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

namespace stepwise {
namespace {

// a scene of the studies: a model with parameters, integrated from t = 0 to t_end
struct StudyScene {
  std::string label;
  std::string model;
  Params params;
  double t_end;
  double time_scale;    // fastest time scale (s): 1/w for the pendulum, 1/rate for the flow
  double frame_extent;  // m: the height of the world a rendered frame shows, for the half-pixel target
  bool dense = true;        // false: methods keeping dense n x n matrices are left out whatever their size
  double implicit_dt = 0;   // s: where the implicit fixed-step methods' sweeps start, if not where accuracy
                            // puts a first-order method's (time_scale / 256: the point of them is larger steps)
};

// a scene without an exact solution is measured against gsl-rk8pd at this tolerance (atol 1e-3 of it): the
// cloth's errors flatten at 3e-13 there, the reference's own
constexpr double reference_rtol = 1e-13;
constexpr std::string_view reference_method = "gsl-rk8pd";

// the rendered frame's height in pixels (1280 x 720): half a pixel of it is the animation's error target
constexpr double frame_pixels = 720;
constexpr double verification_target = 1e-8;

std::vector<StudyScene> ode_scenes() {
  return {// the bob swings through 2 L sin(1 rad) = 1.7 m of a 1 m pendulum: a 2.5 m frame
          {"pendulum", "pendulum", {{"theta0", 1.0}}, 10.0, 0.25, 2.5},
          // the particle moves about 1 m in the unit flow over 1 s
          {"flow-particle", "flow-particle", {}, 1.0, 1.0, 2.0},
          // launched at (10, 10) m/s with drag 0.5/s: 12 m downrange and 4.5 m up in 2 s
          {"projectile", "projectile", {{"drag", 0.5}}, 2.0, 1.0, 12.0},
          // one particle of the particle system without repulsion: three damped oscillators, w = 2 rad/s; it
          // sags g / w^2 = 2.5 m under gravity from within a 2 m box
          {"particle-system", "particle-system", {{"count", 1}, {"repulsion", 0}}, 2.0, 0.5, 5.0},
          // the (1, 2) mode of a 17^2 height field against its exact semi-discrete solution: the seeds' scheme
          // beside the method of lines. The time scale is 16 times the scheme's stability limit (0.044 s), so
          // wave-fd starts at half its limit and rk4 and the Euler family start past theirs (shown diverged)
          // and halve into stability. The frame shows the 1 m pool.
          {"standing-wave", "standing-wave", {{"size", 17}, {"spacing", 1.0 / 16}, {"c", 1}, {"mu", 0.5}, {"mode_m", 1}, {"mode_n", 2}, {"amplitude", 1}}, 2.0,
           16 * wave_stable_dt({17, 1.0 / 16, 1, 0.5}), 1.0}};
}

// the work-precision sweeps' scenes: those above, and the hanging sheet at 6 x 6 (no exact solution: against
// the reference run) released flat for 0.5 s; its time scale 1/omega of its stiffest mode
std::vector<StudyScene> work_precision_scenes() {
  auto scenes = ode_scenes();
  const Params sheet{{"rows", 6}, {"columns", 6}, {"width", 1}, {"height", 1}, {"mass", 0.4}, {"stiffness", 200}, {"shear_stiffness", 100},
                     {"bend_stiffness", 10}, {"damping", 0.05}, {"drag", 0.1}, {"pin_top_corners", 1}, {"pin_corners", 0}, {"wind_coefficient", 0}};
  const auto model = make_model("cloth", sheet);
  const double omega = stiffest_mode(*model, 0, model->initial_state()).omega;
  // the sheet falls for 0.5 s from its 1 m start: a 1.5 m frame. GSL's implicit steppers, with a dense
  // Jacobian by differences each step, take 3-4 s a point at rtol 1e-6 (204 unknowns): left out, cvode-bdf
  // on KLU, implicit-euler on CHOLMOD and Liu's method stand for the implicit methods
  scenes.push_back({"hanging-cloth-6x6", "cloth", sheet, 0.5, 1 / omega, 1.5, false, 0.05});
  return scenes;
}

// methods whose dense n x n matrices exceed this (362 unknowns) are left out of a scene's sweeps: a dense
// LU of the standing wave's 578 unknowns (64 MFLOP) at every step of every point would take the report's
// whole budget, and cvode-bdf (KLU on the sparse Jacobian) is there to represent the implicit methods
constexpr double dense_matrix_budget = 1 << 20;

constexpr std::string_view dense_note =
    "Methods that would keep dense n x n matrices larger than 1 MiB (the standing wave's 578 unknowns: implicit-euler, GSL's implicit "
    "steppers) are left out of a scene; cvode-bdf, with KLU on the sparse Jacobian, stands for the implicit methods there. On the "
    "cloth, GSL's implicit steppers (a dense Jacobian by differences every step: 3-4 s a point at rtol 1e-6) are left out too; "
    "implicit-euler on CHOLMOD and fast-mass-spring join cvode-bdf there.\n\n";

bool in_sweep(const Method& method, const Model& model, bool dense) {
  const double bytes = dense_matrix_bytes(method, model);
  return method_applies(method, model) && bytes <= dense_matrix_budget && (dense || bytes == 0);
}

// the methods of a scene's sweeps, fixed-step ones only if asked
std::vector<const Method*> scene_methods(const StudyScene& scene, bool fixed_only) {
  const auto model = make_model(scene.model, scene.params);
  std::vector<const Method*> chosen;
  for (const auto& method : methods())
    if (in_sweep(method, *model, scene.dense) && (method.fixed_step() || !fixed_only)) chosen.push_back(&method);
  return chosen;
}

// ---- convergence: error against dt for every fixed-step method, with the fitted order

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
                 "increment to z each step instead of taking the difference of two nearly equal levels.\n\n" +
                 std::string(dense_note);

  // one point per (scene, method): its whole sweep of halvings, which the fit needs together
  struct Point {
    const StudyScene* scene;
    const Method* method;
  };
  const auto scenes = ode_scenes();
  std::vector<Point> plan;
  std::vector<std::string> labels;
  for (const auto& scene : scenes)
    for (const Method* method : scene_methods(scene, true)) {
      plan.push_back({&scene, method});
      labels.push_back(fmt::format("{} {}", scene.label, method->name));
    }
  const auto sweeps = ctx.sweep<ConvergenceSweep>(labels, [&](size_t i) {
    const auto model = make_model(plan[i].scene->model, plan[i].scene->params);
    return convergence_sweep(*model, *plan[i].method, plan[i].scene->t_end, halvings, coarse_dt(*plan[i].method, plan[i].scene->time_scale));
  });

  const StudyScene* current = nullptr;
  for (size_t i = 0; i < plan.size(); ++i) {
    const auto& [scene, method] = plan[i];
    const ConvergenceSweep& sweep = sweeps[i];
    if (scene != current) {
      if (current) out.markdown += "\n";
      current = scene;
      out.markdown += fmt::format("### {}\n\n{}| method | order (method table) | observed order | error at coarsest dt | error at finest dt |\n"
                                  "|---|---|---|---|---|\n",
                                  scene->label, add_figure(out.figures, "convergence", scene->label, "Error at t_end against dt, " + scene->label));
    }
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
    out.markdown += fmt::format("| {} | {} | {:.2f} | {} | {} |\n", method->name, method->order.text, sweep.observed_order, sci(coarsest), sci(finest));
  }
  out.markdown += "\n";
  out.tables = {{"convergence", std::move(points)}, {"convergence_orders", std::move(orders)}};
  return out;
}

// ---- work-precision: error against cost for every method, the Pareto fronts, the recommendations

// minimum thread CPU time over `repeats` runs after one discarded warm-up run
Measured timed_run(const Model& model, std::string_view method, const StepControl& control, double t_end, int repeats) {
  Measured best = run_and_measure(model, method, control, t_end, t_end);
  for (int r = 0; r < repeats; ++r) {
    Measured m = run_and_measure(model, method, control, t_end, t_end);
    if (m.result.stats.cpu_seconds < best.result.stats.cpu_seconds || r == 0) best = std::move(m);
  }
  return best;
}

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

StudyOutput work_precision(const StudyContext& ctx) {
  const int repeats = ctx.quick ? 1 : 3;
  const int halvings = ctx.quick ? 4 : 7;
  std::vector<double> rtols;
  for (int e = 2; e <= 12; e += ctx.quick ? 2 : 1) rtols.push_back(std::pow(10.0, -e));

  const auto scenes = work_precision_scenes();
  // the reference states of the scenes without an exact solution
  std::map<const StudyScene*, Eigen::VectorXd> reference;
  for (const auto& scene : scenes)
    if (const auto model = make_model(scene.model, scene.params); !model->has_exact()) {
      const Measured m = run_and_measure(*model, reference_method, StepControl::adaptive(reference_rtol, 1e-3 * reference_rtol), scene.t_end, scene.t_end);
      if (m.result.status != Status::ok)
        throw std::runtime_error(fmt::format("work-precision: the reference run of {} ({}) failed: {}", scene.label, reference_method, m.result.message));
      reference[&scene] = m.result.y_stop;
    }
  std::vector<WorkPoint> plan;
  std::vector<std::string> labels;
  for (const auto& scene : scenes)
    for (const Method* method : scene_methods(scene, false)) {
      WorkPoint point{&scene, method, {}, {}, 0, 0, 0, Status::ok, false};
      if (method->fixed_step())
        for (int k = 0; k <= halvings; ++k) {
          const bool implicit = method->dense != DenseMatrices::none || method->needs.type == needs_mass_spring.type;
          const double coarse = implicit && scene.implicit_dt > 0 ? scene.implicit_dt : coarse_dt(*method, scene.time_scale);
          point.control = StepControl::fixed(coarse / std::pow(2.0, k));
          point.coarsest = k == 0;
          plan.push_back(point);
        }
      if (method->adaptive())
        for (const double rtol : rtols) {
          point.control = StepControl::adaptive(rtol, 1e-3 * rtol);
          point.coarsest = rtol == rtols.front();
          // a low-order method at a tight tolerance needs millions of steps (gsl-rk1imp at 1e-12: 3e7 steps,
          // 30 s): such a point is reported as failed past this budget rather than allowed to stall the report
          point.control.max_steps = 200'000;
          plan.push_back(point);
        }
    }
  for (const auto& p : plan) labels.push_back(fmt::format("{} {} {}", p.scene->label, p.method->name, p.setting()));
  const auto runs = ctx.sweep<WorkPoint>(labels, [&](size_t i) {
    WorkPoint p = plan[i];
    const auto model = make_model(p.scene->model, p.scene->params);
    const Measured m = timed_run(*model, p.method->name, p.control, p.scene->t_end, repeats);
    p.error = m.error;
    if (!model->has_exact() && m.result.status == Status::ok) p.error = max_norm_error(m.result.y_stop, reference.at(p.scene));
    p.rhs_evals = static_cast<double>(m.result.stats.rhs_evals);
    p.cpu_seconds = m.result.stats.cpu_seconds;
    p.steps = m.result.stats.steps;
    p.status = m.result.status;
    return p;
  });

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
  std::string recommendations =
      fmt::format("### Recommendations\n\nPer scene, the cheapest method in CPU time that meets each target, read off the Pareto front "
                  "below: for animation, half a pixel of a {:.0f}-pixel-high frame showing the scene (the frame's height in metres is given; "
                  "the target applies to the state's max-norm error, velocities included, so it errs strict), and for verification "
                  "{:.0e}. The runner-up is the cheapest other method meeting the same target, with its cost as a ratio. A setting marked * is "
                  "the coarsest its method was swept at: a coarser one might meet the target for less.\n\n"
                  "| scene | purpose | target | method | setting | error | CPU (s) | runner-up | its CPU / the best's |\n|---|---|---|---|---|---|---|---|---|\n",
                  frame_pixels, verification_target);
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

    for (const auto& [purpose, target] : {std::pair<std::string, double>{"animation", 0.5 * scene.frame_extent / frame_pixels}, {"verification", verification_target}}) {
      const WorkPoint* best = cheapest_reaching(by_cpu, target);
      if (!best) {
        advice.rows.push_back({scene.label, scene.frame_extent, purpose, target, std::string("none"), std::string(), 0L, NAN, NAN, NAN, std::string("none"), NAN, NAN});
        recommendations += fmt::format("| {} | {} | {:.1e} | none reached it | | | | | |\n", scene.label, purpose, target);
        continue;
      }
      // the runner-up: the cheapest point of any other method that meets the target
      const WorkPoint* runner = nullptr;
      for (const WorkPoint* p : mine)
        if (p->error && *p->error <= target && p->method != best->method && (!runner || p->cpu_seconds < runner->cpu_seconds)) runner = p;
      const std::string runner_name = runner ? fmt::format("{} ({})", runner->method->name, runner->setting()) : "none";
      const double runner_cpu = runner ? runner->cpu_seconds : NAN;
      advice.rows.push_back({scene.label, scene.frame_extent, purpose, target, std::string(best->method->name), best->setting(),
                             static_cast<long>(best->coarsest), *best->error, best->cpu_seconds, best->rhs_evals, runner_name, runner_cpu, runner_cpu / best->cpu_seconds});
      recommendations += fmt::format("| {} ({:g} m frame) | {} | {:.1e} | {} | {}{} | {:.1e} | {:.1e} | {} | {:.1f} |\n", scene.label, scene.frame_extent,
                                     purpose, target, best->method->name, best->setting(), best->coarsest ? " *" : "", *best->error, best->cpu_seconds, runner_name,
                                     runner_cpu / best->cpu_seconds);
    }

    sections += fmt::format("### {}\n\n{}Pareto front in CPU time (no other point is both cheaper and more accurate):\n\n"
                            "| CPU (s) | error | method | setting |\n|---|---|---|---|\n",
                            scene.label, add_figure(out.figures, "work_precision", scene.label, "Work-precision diagram, " + scene.label));
    for (const WorkPoint* p : by_cpu) sections += fmt::format("| {:.2e} | {:.2e} | {} | {} |\n", p->cpu_seconds, *p->error, p->method->name, p->setting());
    sections += "\n";
  }
  out.markdown = recommendations + "\n" +
                 fmt::format("Error at t_end (max norm against the exact solution; for the cloth, against {} at rtol {:.0e}) against cost.", reference_method, reference_rtol) +
                 " Fixed-step methods are swept over dt halvings, "
                 "adaptive ones over rtol (atol = 1e-3 rtol). CPU time is the minimum over repeated runs after a discarded warm-up. "
                 "Failed or diverged points are drawn as crosses at the top of each diagram and stay in the CSV with their status. "
                 "The GPU methods (`gpu-wave`, `gpu-symplectic-euler`, `gpu-cloth`) run their passes on llvmpipe in the calling thread, so "
                 "their CPU time is their whole cost: a pass and a read-back per step, which on these small grids costs more than the "
                 "CPU's step. They compute in float32, which sets a floor: `gpu-wave`'s is its rounded coefficients (the convergence "
                 "section), and on the 6 x 6 sheet `gpu-cloth`'s error rises as dt falls, since an increment h v below u |x| "
                 "(u = 6e-8) is rounded away and the roundings pile up over more steps: float32 explicit cloth wants steps near its "
                 "stability limit.\n\n" +
                 std::string(dense_note) + sections;
  out.tables = {{"work_precision", std::move(points)}, {"work_precision_pareto", std::move(fronts)}, {"recommendations", std::move(advice)}};
  return out;
}

// ---- stability regions: each method's region in the complex plane against the scenes' spectra

StudyOutput stability_regions(const StudyContext& ctx) {
  const long steps = 2000;
  struct SpectrumScene {
    std::string label;
    std::shared_ptr<const Model> model;
    Eigen::VectorXd y0;
    std::function<bool(std::string_view method, double dt)> bounded;  // the measured side
  };
  // the standing wave's grid from a random field (every mode excited) and the cloth's stability sheet from rest
  std::vector<SpectrumScene> scenes;
  {
    const auto scene = ode_scenes().back();
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
  const std::vector<std::string> region_methods{"euler", "rk4", "implicit-euler"};

  std::vector<std::string> labels;
  for (const auto& s : scenes) labels.push_back(s.label + " spectrum");
  const auto spectra = ctx.sweep<Eigen::VectorXcd>(labels, [&](size_t i) { return jacobian_spectrum(*scenes[i].model, 0, scenes[i].y0); });

  struct Limit {
    size_t scene;
    std::string method;
    double predicted = NAN, measured = NAN;
  };
  std::vector<Limit> limits;
  labels.clear();
  for (size_t i = 0; i < scenes.size(); ++i)
    for (const auto& method : region_methods) {
      limits.push_back({i, method, *spectrum_stable_dt(method, spectra[i])});
      labels.push_back(fmt::format("{} {}", scenes[i].label, method));
    }
  const auto measured = ctx.sweep<double>(labels, [&](size_t k) {
    const Limit& l = limits[k];
    // implicit Euler is not probed: its Newton solves on 578 unknowns would cost more than the rest of the study
    if (l.method == "implicit-euler" || !std::isfinite(l.predicted) || l.predicted <= 0) return std::numeric_limits<double>::quiet_NaN();
    const auto& s = scenes[l.scene];
    return bisect_stability([&](double dt) { return s.bounded(l.method, dt); }, l.predicted / 4, l.predicted * 16,
                            tolerance::stability_bisection_width);
  });

  Table spectrum{{"scene", "re", "im"}, {}};
  for (size_t i = 0; i < scenes.size(); ++i)
    for (const auto& lambda : spectra[i]) spectrum.rows.push_back({scenes[i].label, lambda.real(), lambda.imag()});
  Table table{{"scene", "method", "spectrum_dt", "measured_dt", "measured_over_spectrum"}, {}};
  StudyOutput out;
  out.markdown = fmt::format(
      "Why a step fails: a one-step method multiplies each eigen-component of a linear(ised) system by R(h lambda) per step, so it is "
      "stable while every h lambda of the Jacobian's spectrum lies in its region |R(z)| <= 1. The spectra of the standing wave's 17^2 "
      "grid (578 unknowns, mu = 0.5) and of the cloth's 8 x 8 stability sheet (c = 1000 N/m) are drawn times rk4's largest stable "
      "step predicted from them, over the regions of explicit Euler, rk4 and implicit Euler (the whole plane outside the disc about 1). "
      "Predicted: the largest h keeping every h lambda in the region; measured: bisection to 0.1% on {} steps (from a random field for "
      "the wave, from rest for the sheet) staying within 1e6 of the start.\n\n{}"
      "| scene | method | predicted from the spectrum (s) | measured (s) | measured / predicted |\n|---|---|---|---|---|\n",
      steps, add_figure(out.figures, "stability_regions", "", "Stability regions and the scenes' spectra"));
  for (size_t k = 0; k < limits.size(); ++k) {
    const Limit& l = limits[k];
    const double ratio = measured[k] / l.predicted;
    table.rows.push_back({scenes[l.scene].label, l.method, l.predicted, measured[k], ratio});
    out.markdown += fmt::format("| {} | {} | {} | {} | {} |\n", scenes[l.scene].label, l.method,
                                std::isinf(l.predicted) ? std::string("any (A-stable)") : fmt::format("{:.4g}", l.predicted),
                                std::isnan(measured[k]) ? std::string("—") : fmt::format("{:.4g}", measured[k]),
                                std::isnan(ratio) ? std::string("—") : fmt::format("{:.3f}", ratio));
  }
  out.markdown += "\nrk4's measured limits match the spectrum's; explicit Euler's probe finds several times its prediction (up to the "
                  "bracket's 16): near its limit its growth per step, |1 + h lambda| - 1, is so small on the weakly damped modes that "
                  "2000 steps do not show it, the cloth study's finding. Symplectic Euler has no R(z): it maps (x, v) pairs, and on an undamped oscillator it is stable for h omega < 2, "
                  "the segment of the imaginary axis |z| < 2 (the cloth study's table).\n\n";
  out.tables = {{"stability_spectrum", std::move(spectrum)}, {"stability_limits", std::move(table)}};
  return out;
}

}  // namespace

std::vector<Study> accuracy_studies() {
  return {{"work-precision", "Accuracy against cost, and the recommendations", work_precision},
          {"convergence", "Convergence", convergence},
          {"stability-regions", "Stability: the methods' regions against the scenes' spectra", stability_regions}};
}

}  // namespace stepwise
