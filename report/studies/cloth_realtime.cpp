// The report's study: cloth-realtime: the seeds' 32 x 32 flag over 2 s, each method's position error against
// its CPU time per simulated second, beside the real-time budget and half a pixel of a 720-pixel frame.
#include "report/studies/study_scenes.hpp"

#include "solvers/capabilities/second_order.hpp"

namespace stepwise {
namespace {

// the quick report's flag runs a quarter as long: the reference's rk4 runs are most of the study's cost
constexpr double full_t_end = 2.0, quick_t_end = 0.5;
// the reference: rk4 far below its stability limit (the stiffest mode's omega h ~ 0.5 at 2.5e-4 s), checked
// against itself at half the step
constexpr double reference_dt = 2.5e-4;

struct Point {
  std::string method;
  StepControl control;
  std::string setting;
};

// the methods and settings: the implicit ones at frame-sized steps and below, the explicit ones below their
// stability limit (~1.5e-3 s for symplectic Euler here), the adaptive ones at loose tolerances (an animation's
// accuracy)
std::vector<Point> realtime_plan(bool quick) {
  std::vector<Point> points;
  const auto fixed = [&](const char* method, std::initializer_list<double> dts) {
    for (const double dt : dts) points.push_back({method, StepControl::fixed(dt), fmt::format("dt {:.3g}", dt)});
  };
  const auto adaptive = [&](const char* method, std::initializer_list<double> rtols) {
    for (const double rtol : rtols) {
      StepControl c = StepControl::adaptive(rtol, 1e-3 * rtol);
      c.max_steps = 20'000;
      points.push_back({method, c, fmt::format("rtol {:.0e}", rtol)});
    }
  };
  // xpbd (Macklin et al.'s small steps: a 1/60 s frame in substeps of one iteration), the springs read as
  // compliant constraints of the same stiffness (their Voigt damping left out: XPBD damps by itself)
  const auto small_steps = [&](std::initializer_list<int> substeps) {
    for (const int s : substeps) {
      StepControl c = StepControl::fixed(1.0 / 60);
      c.settings["substeps"] = s;
      c.settings["iterations"] = 1;
      points.push_back({"xpbd", c, fmt::format("1/60 s, {} substeps", s)});
    }
  };
  // vbd (Chen et al. 2024: one step a frame, its sweeps over the coloured nodes)
  const auto sweeps = [&](std::initializer_list<int> counts) {
    for (const int k : counts) {
      StepControl c = StepControl::fixed(1.0 / 60);
      c.settings["iterations"] = k;
      points.push_back({"vbd", c, fmt::format("1/60 s, {} sweeps", k)});
    }
  };
  // the explicit high-order methods too: on this flag only an accurate trajectory stays within half a pixel
  // (small early differences grow as it billows), and they are stable at ~1.5e-3 s
  if (quick) {
    // (implicit Euler at 1/240 s, 3 s of CPU, is the full report's: 0.13 m off, it says no more than 1/60 does)
    fixed("implicit-euler", {1.0 / 60});
    fixed("implicit-euler-newton", {1.0 / 60});
    fixed("fast-mass-spring", {1.0 / 60, 1.0 / 240});
    fixed("symplectic-euler", {1e-3});
    fixed("gpu-cloth", {1e-3});
    fixed("rk4", {1e-3});
    adaptive("tsitouras54", {1e-4});
    small_steps({20});
    sweeps({10});
  } else {
    fixed("implicit-euler", {1.0 / 30, 1.0 / 60, 1.0 / 120, 1.0 / 240, 1.0 / 480});
    fixed("implicit-euler-newton", {1.0 / 30, 1.0 / 60, 1.0 / 120, 1.0 / 240});
    fixed("fast-mass-spring", {1.0 / 30, 1.0 / 60, 1.0 / 120, 1.0 / 240, 1.0 / 480});
    fixed("symplectic-euler", {1e-3, 5e-4, 2.5e-4});
    fixed("gpu-cloth", {1e-3, 5e-4});
    fixed("rk4", {1e-3, 5e-4});
    adaptive("tsitouras54", {1e-3, 1e-4, 1e-6});
    small_steps({5, 10, 20, 40, 80});
    sweeps({2, 5, 10, 20});
    // no ARKODE point: its Newton iterations on KLU with 6 144 unknowns took 42-53 s of CPU per simulated second
    // at rtol 1e-2 (ark324 106 s, kvaerno43 84 s for the 2 s flag), 40-50 times real time and a third of the
    // full report's 10 minutes; the work-precision study measures ARKODE's implicit methods on a cloth (the
    // 6 x 6 hanging cloth)
  }
  return points;
}

StudyOutput cloth_realtime(const StudyContext& ctx) {
  const double t_end = ctx.quick ? quick_t_end : full_t_end;
  const auto flag = make_model("cloth", {});  // the model's defaults are the seeds' flag (scenes/flag.toml)
  const Eigen::Index positions = flag->as<SecondOrderView>()->positions;
  const double half_pixel = 0.5 * flag_frame_extent / frame_pixels;
  const std::vector<Point> points = realtime_plan(ctx.quick);

  // the two reference runs, then every point
  std::vector<std::string> labels{"reference rk4", "reference rk4 (half step)"};
  // expected CPU time (ns) for the sweep's order and time-left estimate, measured on this flag: a step of an
  // explicit method ~25 ns an unknown and stage, an implicit step ~5 ms, a GPU pass ~0.25 ms, an adaptive
  // explicit point ~2 s
  const double n = static_cast<double>(flag->size());
  std::vector<double> costs{t_end / reference_dt * 100 * n, 2 * t_end / reference_dt * 100 * n};
  // each method a group of the time-left estimate, which learns each one's ratio to these costs from its own
  // points (one ratio for all lets the first method's points, mis-estimated, scale every other method's
  // estimate the same way)
  std::vector<std::string> groups{"rk4", "rk4"};
  for (const auto& p : points) {
    labels.push_back(fmt::format("{} {}", p.method, p.setting));
    groups.push_back(p.method);
    const double steps = p.control.dt ? t_end / *p.control.dt : 0;
    // by the method table's attributes: an explicit fixed-step method (one with a derived mode limit) takes as
    // many stages as its order, up to rk4's four
    const Method& m = *find_method(p.method);
    costs.push_back(!p.control.dt                     ? 2e9
                    : m.source == Source::opengl_shader ? steps * 2.5e5
                    : m.family == Family::vertex_block_descent ? steps * m.setting(p.control, "iterations") * 150 * n
                    : m.option("substeps")              ? steps * m.setting(p.control, "substeps") * m.setting(p.control, "iterations") * 25 * n
                    : m.stability.oscillator_dt         ? steps * 25 * n * m.order.min
                                                        : steps * 5e6);
  }
  const auto runs = ctx.sweep<Measured>(labels, [&](size_t i) {
    const auto model = make_model("cloth", {});
    if (i < 2) return run_and_measure(*model, "rk4", StepControl::fixed(reference_dt / static_cast<double>(1 + i)), t_end, t_end);
    const Point& p = points[i - 2];
    return run_and_measure(*model, p.method, p.control, t_end, t_end);
  }, costs, groups);
  for (size_t i = 0; i < 2; ++i)
    if (runs[i].result.status != Status::ok)
      throw std::runtime_error(fmt::format("cloth-realtime: the reference run failed: {}", runs[i].result.message));
  const Eigen::VectorXd reference = runs[1].result.y_stop.head(positions);
  // rk4's error at the half step, estimated from the two (Richardson: the difference over 2^4 - 1)
  const double reference_error = (runs[0].result.y_stop.head(positions) - reference).lpNorm<Eigen::Infinity>() / 15;

  Table table{{"method", "setting", "steps", "cpu_seconds", "cpu_per_simulated_second", "position_error", "status", "half_pixel_m"}, {}};
  for (size_t k = 0; k < points.size(); ++k) {
    const Measured& m = runs[k + 2];
    const bool ok = m.result.status == Status::ok;
    const double error = ok ? (m.result.y_stop.head(positions) - reference).lpNorm<Eigen::Infinity>() : NAN;
    table.rows.push_back({points[k].method, points[k].setting, m.result.stats.steps, m.result.stats.cpu_seconds,
                          m.result.stats.cpu_seconds / t_end, error, std::string(to_string(m.result.status)), half_pixel});
  }

  // per method: the cheapest setting within half a pixel, and how far it is from real time; or, where none is
  // within half a pixel, its most accurate one and how far that misses
  Table verdicts{{"method", "setting", "position_error", "cpu_per_simulated_second", "verdict"}, {}};
  std::vector<std::string> realtime;
  for (const auto& p : points) {
    if (!verdicts.rows.empty() && std::get<std::string>(verdicts.rows.back()[0]) == p.method) continue;
    std::optional<size_t> cheapest, best;
    for (size_t k = 0; k < points.size(); ++k) {
      if (points[k].method != p.method) continue;
      const double e = std::get<double>(table.rows[k][5]), c = std::get<double>(table.rows[k][4]);
      if (!std::isfinite(e)) continue;
      if (e <= half_pixel && (!cheapest || c < std::get<double>(table.rows[*cheapest][4]))) cheapest = k;
      if (!best || e < std::get<double>(table.rows[*best][5])) best = k;
    }
    const std::optional<size_t> shown = cheapest ? cheapest : best;
    if (!shown) {
      verdicts.rows.push_back({p.method, std::string("-"), NAN, NAN, std::string("every setting failed")});
      continue;
    }
    const double e = std::get<double>(table.rows[*shown][5]), c = std::get<double>(table.rows[*shown][4]);
    std::string verdict;
    if (cheapest && c <= 1) {
      verdict = fmt::format("real time within half a pixel, {:.2f} of the budget", c);
      realtime.push_back(p.method);
    } else if (cheapest) {
      verdict = fmt::format("within half a pixel at {:.2g} times real time", c);
    } else {
      verdict = fmt::format("never within half a pixel (best {:.2g} pixel, at {:.2g} times real time)", e / (2 * half_pixel), c);
    }
    verdicts.rows.push_back({p.method, points[*shown].setting, e, c, verdict});
  }

  StudyOutput out;
  out.markdown = fmt::format(
      "The seeds' 32 x 32 flag (6 144 unknowns, wind through the normals, gusting) over {:g} s: each method's largest "
      "node position error at t = {:g} s against its CPU time per simulated second, on one core. The reference is rk4 at dt "
      "{:.3g} s (its own error, from the run at twice that step: {}). The vertical line is the real-time budget (1/60 s of CPU "
      "per 1/60 s of simulated time); the horizontal one half a pixel of a {:.0f}-pixel-high frame {:g} m tall ({:.2g} m).\n\n",
      t_end, t_end, reference_dt / 2, sci(reference_error), frame_pixels, flag_frame_extent, half_pixel);
  FigureSpec spec{.title = fmt::format("The 32 x 32 flag over {:g} s: accuracy against cost", t_end),
                  .panels = {{.x_label = "CPU seconds per simulated second", .y_label = "largest node position error (m)", .log_x = true, .log_y = true,
                              .layers = {{.table = "cloth_realtime", .x = "cpu_per_simulated_second", .y = "position_error", .series = "method",
                                          .hover = {{"setting", "setting"}}}},
                              .lines = {{'x', 1.0, "real time (one core)"}, {'y', half_pixel, "half a pixel (720-pixel frame)"}}}}};
  out.markdown += add_figure(out.figures, "cloth_realtime", "", std::move(spec), "The flag: position error against CPU time per simulated second");
  out.markdown += realtime.empty()
                      ? "**No method runs the flag in real time within half a pixel on one core here**; the table says by how much each misses.\n\n"
                      : fmt::format("**In real time within half a pixel on one core: {}.**\n\n", fmt::join(realtime, ", "));
  out.markdown += markdown_table(verdicts, {{"method", "method", {}, {}},
                                            {"setting", "cheapest setting within half a pixel (else the most accurate)", {}, {}},
                                            {"position_error", "position error (m)", shown_as("sci"), {}},
                                            {"cpu_per_simulated_second", "CPU s per simulated s", shown_as("{:.3g}"), {}},
                                            {"verdict", "verdict", {}, {}}});
  out.tables.emplace_back("cloth_realtime", std::move(table));
  out.tables.emplace_back("cloth_realtime_verdicts", std::move(verdicts));
  return out;
}

}  // namespace

Study cloth_realtime_study() { return {"cloth-realtime", "The flag in real time", cloth_realtime}; }

}  // namespace stepwise
