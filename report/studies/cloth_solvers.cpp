// The report's study: cloth-solvers: Vertex Block Descent's claims (Chen, Liu, Yang & Yuksel 2024: unconditional
// stability, convergence per unit of compute better than XPBD's, a result that degrades gracefully as the iteration
// budget is cut) measured on the seeds' 32 x 32 flag at 1/60 s, springs and continuum, beside the solvers of the same
// step: backward Euler by Newton (the converged step every other is measured against), its linearised step, fast
// mass-spring and xpbd. Each row: the CPU per simulated second, how far its one step from the flag in motion leaves
// the incremental potential above its minimum (potential_gap, G(x) - G(x*), x* Newton's to 1e-9 m/s), and how far
// its run is from converged backward Euler's run at the same step over the frames (pixels_off, a 720-pixel frame
// 1.5 m tall).
#include "report/studies/study_scenes.hpp"

#include "solvers/capabilities/second_order.hpp"
#include "solvers/incremental_potential.hpp"
#include "solvers/run_support.hpp"

#include <random>

namespace stepwise {
namespace {


struct SolverRow {
  std::string model;   // springs, continuum, continuum-stiff (E x 100), springs-scrambled (every node at random)
  std::string method;
  double dt = engine_frame;
  int iterations = 1;  // vbd's sweeps a step; xpbd's a substep
  int substeps = 1;
  std::string start = "inertial";  // vbd's (--start): the inertial position, or the paper's adaptive guess
};

Params model_params(const std::string& model) {
  if (model == "continuum") return {{"continuum", 1}};
  if (model == "continuum-stiff") return {{"continuum", 1}, {"E", 100 * 5e5}};
  return {};
}

// the true motion's step: continuum-cloth's reference (200 steps of its 1/15 s frames), which divides 1/60 and 1/30 s
constexpr double true_motion_dt = 1.0 / 3000;

// the rows: the iteration budgets and substeps at 1/60 s, then the stability rows at 1/30 s and the scrambled start
std::vector<SolverRow> solver_plan(bool quick) {
  const std::vector<int> sweeps = quick ? std::vector<int>{1, 5, 20} : std::vector<int>{1, 2, 5, 10, 20};
  const std::vector<int> continuum_sweeps = quick ? std::vector<int>{5} : sweeps;  // the continuum's sweeps cost 8 times the springs
  const std::vector<int> substeps = quick ? std::vector<int>{20} : std::vector<int>{5, 20, 80};
  const std::vector<int> accelerated = quick ? std::vector<int>{20} : std::vector<int>{5, 10, 20};  // Chebyshev's from sweep 2
  std::vector<SolverRow> rows;
  for (const char* model : {"springs", "continuum"}) {
    rows.push_back({model, "implicit-euler-newton"});
    rows.push_back({model, "implicit-euler"});
    for (const int k : std::string(model) == "springs" ? sweeps : continuum_sweeps) rows.push_back({model, "vbd", engine_frame, k});
    for (const int k : std::string(model) == "springs" ? accelerated : continuum_sweeps) rows.push_back({model, "vbd-chebyshev", engine_frame, k});
  }
  for (const int k : quick ? std::vector<int>{5} : std::vector<int>{1, 5, 20}) rows.push_back({"springs", "vbd", engine_frame, k, 1, "adaptive"});
  rows.push_back({"springs", "fast-mass-spring"});
  for (const int s : substeps) rows.push_back({"springs", "xpbd", engine_frame, 1, s});
  for (const char* model : quick ? std::vector<const char*>{"springs"} : std::vector<const char*>{"springs", "continuum-stiff"}) {
    rows.push_back({model, "implicit-euler-newton", 1.0 / 30});
    rows.push_back({model, "vbd", 1.0 / 30, 10});
  }
  rows.push_back({"springs-scrambled", "vbd", engine_frame, 10});
  return rows;
}

// the true motion: rk4 at 1/3000 s (converged: continuum-cloth's reference step, its offset from the run at twice the
// step Richardson-estimated there), the springs and the continuum from their flat start, sampled every 1/60 s. The
// stiff continuum's rk4 would take ten times the steps (its limit is E's square root lower): its rows say n/a, and so
// do the continuum's in a quick report (its rk4, 2 CPU s of the preview's minute)
std::vector<std::string> true_motion_models(bool quick) { return quick ? std::vector<std::string>{"springs"} : std::vector<std::string>{"springs", "continuum"}; }
std::vector<Measured> true_motions(const StudyContext& ctx, double t_end) {
  const std::vector<std::string> models = true_motion_models(ctx.quick);
  std::vector<std::string> labels;
  for (const auto& model : models) labels.push_back(fmt::format("cloth-solvers {} true motion (rk4 at {:.3g} s)", model, true_motion_dt));
  const auto truths = ctx.sweep<Measured>(labels, [&](size_t i) {
    const auto model = make_model("cloth", model_params(models[i]));
    StepControl c = StepControl::fixed(true_motion_dt);
    c.observe = [](const Eigen::VectorXd& y) { return y; };
    return run_and_measure(*model, "rk4", c, t_end, engine_frame);
  }, std::vector<double>(models.size(), t_end / true_motion_dt * 5e5));  // an rk4 step ~0.25 ms (springs), 0.5 ms (continuum)
  for (size_t i = 0; i < truths.size(); ++i)
    if (truths[i].result.status != Status::ok)
      throw std::runtime_error(fmt::format("cloth-solvers: the {}'s true motion failed: {}", models[i], truths[i].result.message));
  return truths;
}

// every node of the flag placed at random in a cube the sheet's size about its centre, at rest (the paper's test)
Eigen::VectorXd scrambled(const Model& flag) {
  Eigen::VectorXd y = flag.initial_state();
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  const Eigen::Index n = y.size() / 2;
  for (Eigen::Index i = 0; i < n; i += 3) y.segment<3>(i) = Eigen::Vector3d(u(rng), -0.5 + u(rng), u(rng));
  y.tail(n).setZero();
  return y;
}

// how far the scrambled start has recovered its shape, in the springs' elastic energy: at its start and last frame, beside the flag's
// from its flat start at its last frame (converged backward Euler's)
std::string recovery_text(const Trajectory& run, const Trajectory& reference) {
  const auto flag = make_model("cloth", {});
  const Eigen::Index positions = flag->as<SecondOrderView>()->positions;
  const auto& psi = flag->as<MassSpringView>()->potential;
  return fmt::format(
      "From every node scrambled, vbd's springs' elastic energy falls from {:.3g} J at the start to {:.3g} J at {:g} s, where the "
      "flag's from its flat start is {:.3g} J. ",
      psi(scrambled(*flag).head(positions)), psi(run.y.back().head(positions)), run.t.back(), psi(reference.y.back().head(positions)));
}

// the findings, first: each method's rows at 1/60 s, the paper's claim read off G, and the stability rows
std::string findings(const Table& table, const std::vector<SolverRow>& rows, double t_end, const std::string& recovery) {
  // the findings: each method's rows at 1/60 s, cheapest first, as "N px at C CPU s/s (setting)"
  const auto cell = [&](size_t k, const char* column) { return std::get<double>(cell_of(table, table.rows[k], column)); };
  const auto said = [&](const std::string& model, const std::string& method, const std::string& start = "inertial") {
    std::vector<std::string> parts;
    for (size_t k = 0; k < rows.size(); ++k)
      if (rows[k].model == model && rows[k].method == method && rows[k].dt == engine_frame && rows[k].start == start)
        parts.push_back(fmt::format("{:.0f} px{} at {:.2g} CPU s/s{}", cell(k, "pixels_off"),
                                    std::isnan(cell(k, "pixels_off_true_motion")) ? std::string() : fmt::format(" ({:.0f} from the true motion)", cell(k, "pixels_off_true_motion")),
                                    cell(k, "cpu_per_simulated_second"),
                                    method.starts_with("vbd") ? fmt::format(" ({} sweep{}, G − G* {:.2g} J)", rows[k].iterations, rows[k].iterations == 1 ? "" : "s", cell(k, "potential_gap"))
                                    : method == "xpbd"        ? fmt::format(" ({} substeps)", rows[k].substeps)
                                                              : fmt::format(" (G − G* {:.2g} J)", cell(k, "potential_gap"))));
    return fmt::format("{} {}", method, fmt::join(parts, ", "));
  };
  // backward Euler's own offset from the true motion: what no solver of its step can do better than
  std::string own;
  for (size_t k = 0; k < rows.size(); ++k)
    if (rows[k].method == "implicit-euler-newton" && rows[k].dt == engine_frame && !std::isnan(cell(k, "pixels_off_true_motion")))
      own += fmt::format("{}{:.0f} px ({})", own.empty() ? "" : ", ", cell(k, "pixels_off_true_motion"), rows[k].model);
  std::string stability;
  for (size_t k = 0; k < rows.size(); ++k)
    if (rows[k].dt != engine_frame || rows[k].model == "springs-scrambled")
      stability += fmt::format("{}{} {} at {}: {}", stability.empty() ? "" : "; ", rows[k].model, rows[k].method,
                               rows[k].dt == engine_frame ? std::string("1/60 s") : std::string("1/30 s"), std::get<std::string>(cell_of(table, table.rows[k], "status")));
  // the paper's claim read off G: vbd's most sweeps against the linearised step's one solve, on the springs
  std::optional<size_t> most_sweeps, linearised;
  for (size_t k = 0; k < rows.size(); ++k) {
    if (rows[k].model != "springs" || rows[k].dt != engine_frame) continue;
    if (rows[k].method == "vbd" && rows[k].start == "inertial" && (!most_sweeps || rows[k].iterations > rows[*most_sweeps].iterations)) most_sweeps = k;
    if (rows[k].method == "implicit-euler") linearised = k;
  }
  const std::string verdict =
      most_sweeps && linearised
          ? fmt::format("After {} sweeps Vertex Block Descent's step leaves G {:.3g} times as far above its minimum as the linearised step's one "
                        "solve{}.",
                        rows[*most_sweeps].iterations, cell(*most_sweeps, "potential_gap") / cell(*linearised, "potential_gap"),
                        cell(*most_sweeps, "potential_gap") > cell(*linearised, "potential_gap")
                            ? ": its Gauss–Seidel sweeps, each node alone, close the gap slowly on this stiff flag, whose slow modes span the sheet"
                            : "")
          : std::string();
  // what Chebyshev's acceleration buys: the accelerated and plain sweeps at the most sweeps both ran, on the springs
  std::string acceleration;
  for (size_t a = 0; a < rows.size(); ++a)
    for (size_t p = 0; p < rows.size(); ++p)
      if (rows[a].model == "springs" && rows[a].dt == engine_frame && rows[a].method == "vbd-chebyshev" && rows[p].model == "springs" &&
          rows[p].dt == engine_frame && rows[p].method == "vbd" && rows[p].start == "inertial" && rows[p].iterations == rows[a].iterations)
        acceleration = fmt::format(
            "Chebyshev's acceleration of the sweeps (ρ {:g}) leaves G {:.3g} times closer to its minimum after {} sweeps, and the run {:.3g} times "
            "closer to converged backward Euler's, for {:.2g} times the CPU. ",
            find_method("vbd-chebyshev")->option("rho")->fallback, cell(p, "potential_gap") / cell(a, "potential_gap"), rows[a].iterations,
            cell(p, "pixels_off") / cell(a, "pixels_off"), cell(a, "cpu_per_simulated_second") / cell(p, "cpu_per_simulated_second"));
  return fmt::format(
      "**Off converged backward Euler at 1/60 s on the 32 × 32 flag over {:g} s — springs: {}; {} from the paper's adaptive start; {}; {}; {}; {}. Continuum: {}; {}; {}. Converged "
      "backward Euler is itself {} from the true motion.** {} {}"
      "Stability (the rows at 1/30 s, continuum-stiff being the continuum at 100 × E, and vbd from every node scrambled): {}. {}Each row's G − G* is how far "
      "its one step from the flag in motion leaves G above its minimum (J, Newton's to 1e-9 m/s); its pixels, how far its "
      "run is from converged backward Euler's at the same step (how well it solves backward Euler), and from the true motion, rk4 at "
      "1/3000 s (how well it animates: converged backward Euler's own offset is its rows'), the largest node offset over the frames in a "
      "720-pixel frame 1.5 m tall (the scrambled start: at the last frame, off backward Euler only; the true motion of the stiff "
      "continuum, and in a quick report of the continuum, is not run). A billowing flag magnifies small differences: the "
      "offsets rank the methods, they do not measure one step. xpbd steps the springs as compliant constraints without "
      "their Voigt damping: part of its offset is that model's. One core; vbd's colours share no term, and its answer is "
      "the same on any number of threads.\n\n",
      t_end, said("springs", "vbd"), said("springs", "vbd", "adaptive"), said("springs", "vbd-chebyshev"), said("springs", "xpbd"), said("springs", "implicit-euler"),
      said("springs", "fast-mass-spring"), said("continuum", "vbd"), said("continuum", "vbd-chebyshev"), said("continuum", "implicit-euler"), own, verdict,
      acceleration, stability, recovery);
}

// G - G* against the sweeps (vbd, plain and accelerated) and against the CPU (every method's one step, the springs)
FigureSpec gap_figure() {
  const std::string at_frame = fmt::format("{}", engine_frame);
  return {
      .title = "The 32 x 32 flag at 1/60 s: how far one step leaves the incremental potential above its minimum",
      .panels = {{.title = "against vbd's sweeps",
                  .x_label = "sweeps a step",
                  .y_label = "G - G* (J)",
                  .log_x = true,
                  .log_y = true,
                  .layers = {{.table = "cloth_solvers", .x = "iterations", .y = "potential_gap", .series = "method", .split = {"model"}, .split_dashed = true,
                              .label = "{} ({model})", .where = {{"method", {"vbd", "vbd-chebyshev"}}, {"dt", {at_frame}}, {"model", {"springs", "continuum"}}}}}},
                 {.title = "against the CPU, springs",
                  .x_label = "CPU seconds per simulated second",
                  .y_label = "G - G* (J)",
                  .log_x = true,
                  .log_y = true,
                  .layers = {{.table = "cloth_solvers", .x = "cpu_per_simulated_second", .y = "potential_gap", .series = "method",
                              .where = {{"dt", {at_frame}}, {"model", {"springs"}}}, .complete = {"potential_gap"},
                              .hover = {{"iterations", "sweeps"}, {"substeps", "substeps"}}}}}}};
}

}  // namespace

StudyOutput cloth_solvers(const StudyContext& ctx) {
  const double t_end = ctx.quick ? 0.25 : 1.0;
  const std::vector<SolverRow> rows = solver_plan(ctx.quick);
  std::vector<std::string> labels;
  for (const SolverRow& r : rows)
    labels.push_back(fmt::format("cloth-solvers {} {} dt {:.3g} iterations {} substeps {} start {}", r.model, r.method, r.dt, r.iterations, r.substeps, r.start));
  const auto control_of = [](const SolverRow& r) {
    StepControl c = StepControl::fixed(r.dt);
    if (const Method* m = find_method(r.method); m->option("iterations")) {
      c.settings["iterations"] = r.iterations;
      c.settings["substeps"] = r.substeps;
      if (const MethodOption* start = m->option("start")) c.settings["start"] = start->parse(r.start);
    }
    c.observe = [](const Eigen::VectorXd& y) { return y; };  // the whole state at each frame
    return c;
  };
  const auto runs = ctx.sweep<Measured>(labels, [&](size_t i) {
    const SolverRow& r = rows[i];
    const auto model = make_model("cloth", model_params(r.model == "springs-scrambled" ? "springs" : r.model));
    // a frame each step at 1/30 s (a fixed step ends at each output time: frames of 1/60 s would halve it)
    if (r.model != "springs-scrambled") return run_and_measure(*model, r.method, control_of(r), t_end, std::max(engine_frame, r.dt));
    Measured m;
    m.t_out = output_times(t_end, engine_frame);
    m.result = make_integrator(r.method, control_of(r))->integrate(*model, 0.0, scrambled(*model), m.t_out);
    return m;
  });

  const std::vector<Measured> truths = true_motions(ctx, t_end);
  const std::vector<std::string> truth_models = true_motion_models(ctx.quick);
  const auto truth_of = [&](const SolverRow& r) {
    const auto at = std::find(truth_models.begin(), truth_models.end(), r.model);
    return at == truth_models.end() ? nullptr : &truths[static_cast<size_t>(at - truth_models.begin())];
  };

  // converged backward Euler's run at each model and step: the reference of its rows
  const auto reference_of = [&](const SolverRow& r) -> const Measured* {
    const std::string model = r.model == "springs-scrambled" ? "springs" : r.model;
    for (size_t k = 0; k < rows.size(); ++k)
      if (rows[k].model == model && rows[k].method == "implicit-euler-newton" && rows[k].dt == r.dt) return &runs[k];
    return nullptr;
  };
  const Eigen::Index positions = make_model("cloth", {})->as<SecondOrderView>()->positions;
  const double pixel = flag_frame_extent / frame_pixels;
  // the largest node offset over the run's frames from the reference's at the same times (the scrambled start: at
  // the last frame only), in pixels; both sampled at whole frames, the reference as often as the run or more
  const auto pixels_off = [&](const Trajectory& run, const Trajectory& reference, bool last_only) {
    double largest = 0;
    size_t k = 0;
    for (size_t f = last_only ? run.y.size() - 1 : 0; f < run.y.size(); ++f) {
      while (k + 1 < reference.t.size() && reference.t[k] < run.t[f] - engine_frame / 4) ++k;
      if (k >= reference.t.size() || std::abs(reference.t[k] - run.t[f]) > engine_frame / 4) continue;
      for (Eigen::Index i = 0; i < positions; i += 3) largest = std::max(largest, (run.y[f].segment<3>(i) - reference.y[k].segment<3>(i)).norm());
    }
    return largest / pixel;
  };
  // one step of each method from the flag in motion (the reference's state halfway), and G there
  const auto potential_gap = [&](const SolverRow& r, const Measured& reference) {
    if (r.model == "springs-scrambled" || reference.result.status != Status::ok) return std::numeric_limits<double>::quiet_NaN();
    const auto model = make_model("cloth", model_params(r.model));
    const size_t middle = reference.result.trajectory.y.size() / 2;
    const double t0 = reference.result.trajectory.t[middle];
    const Eigen::VectorXd& y0 = reference.result.trajectory.y[middle];
    const std::vector<double> t_out{t0 + r.dt};
    StepControl c = control_of(r);
    c.observe = nullptr;
    const RunResult step = make_integrator(r.method, c)->integrate(*model, t0, y0, t_out);
    if (step.status != Status::ok) return std::numeric_limits<double>::quiet_NaN();
    Stats stats;
    const CountedSystem system(*model, stats);
    IncrementalPotential G(system, *system.as<MassSpringView>());
    G.start(t0, y0, r.dt);
    Eigen::VectorXd x = G.inertial();
    PotentialNewton newton(NewtonOnPotential{.velocity_tolerance = 1e-9});
    if (!newton.minimise(G, x, stats).empty()) return std::numeric_limits<double>::quiet_NaN();
    return std::max(0.0, G.value(step.y_stop.head(positions)) - G.value(x));
  };
  Table table{{"model", "method", "dt", "iterations", "substeps", "start", "threads", "cpu_per_simulated_second", "potential_gap", "pixels_off", "pixels_off_true_motion",
               "status"}, {}};
  for (size_t k = 0; k < rows.size(); ++k) {
    const SolverRow& r = rows[k];
    const Measured& m = runs[k];
    const Measured* reference = reference_of(r);
    const bool ok = m.result.status == Status::ok && reference && reference->result.status == Status::ok;
    const Measured* truth = truth_of(r);
    table.rows.push_back({r.model, r.method, r.dt, long{r.method.starts_with("vbd") || r.method == "xpbd" ? r.iterations : 0}, long{r.substeps},
                          r.method.starts_with("vbd") ? r.start : std::string(), long{1},
                          m.result.stats.cpu_seconds / t_end, ok ? potential_gap(r, *reference) : NAN,
                          ok ? pixels_off(m.result.trajectory, reference->result.trajectory, r.model == "springs-scrambled") : NAN,
                          m.result.status == Status::ok && truth ? pixels_off(m.result.trajectory, truth->result.trajectory, false) : NAN,
                          std::string(to_string(m.result.status))});
  }

  std::string recovery;
  for (size_t k = 0; k < rows.size(); ++k)
    if (const Measured* reference = reference_of(rows[k]); rows[k].model == "springs-scrambled" && reference && runs[k].result.status == Status::ok &&
                                                            reference->result.status == Status::ok)
      recovery = recovery_text(runs[k].result.trajectory, reference->result.trajectory);
  StudyOutput out;
  out.markdown = findings(table, rows, t_end, recovery);
  out.markdown += add_figure(out.figures, "cloth_solvers", "", gap_figure(), "The flag's one step: G − G* against sweeps and against CPU");
  out.markdown += markdown_table(table, {{"model", "model"},
                                         {"method", "method"},
                                         {"dt", "dt (s)", shown_as("{:.4f}")},
                                         {"iterations", "sweeps"},
                                         {"substeps", "substeps"},
                                         {"start", "start"},
                                         {"cpu_per_simulated_second", "CPU s per simulated s", shown_as("{:.3g}")},
                                         {"potential_gap", "G − G* (J)", shown_as("sci")},
                                         {"pixels_off", "px off backward Euler", shown_as("{:.3g}")},
                                         {"pixels_off_true_motion", "px off the true motion", shown_as("{:.3g}")},
                                         {"status", "status"}});
  out.markdown += "\n";
  out.tables.emplace_back("cloth_solvers", std::move(table));
  return out;
}

Study cloth_solvers_study() { return {"cloth-solvers", "Cloth: Vertex Block Descent beside xpbd and Newton", cloth_solvers}; }

}  // namespace stepwise
