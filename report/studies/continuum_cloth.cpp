// The report's study: the spring cloth against the continuum (the second seed's two cloths), at rest. What
// material the spring mesh is (its Poisson's ratio and Young's modulus, measured on a stretched strip as for
// the finite elements), and how the hanging sheet's sag and bottom width change as each mesh is refined.
#include "report/studies/study_scenes.hpp"
#include "solvers/capabilities/second_order.hpp"

#include "verification/continuum_checks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace stepwise {
namespace {

constexpr double stretch = material_strip_strain;
constexpr int strip_rows = material_strip_rows;
constexpr double strip_E = 5e5;   // the continuum strips' Young's modulus (Pa)

// the convergence order p of a quantity on meshes of spacing h1 > h2 > h3 from its three values, solving
// (q1 - q2) / (q2 - q3) = (h1^p - h2^p) / (h2^p - h3^p) by bisection (the spacings are not exactly halved)
std::optional<double> observed_order(double h1, double h2, double h3, double q1, double q2, double q3) {
  const double ratio = (q1 - q2) / (q2 - q3);
  if (!(ratio > 0) || !std::isfinite(ratio)) return std::nullopt;
  const auto f = [&](double p) { return (std::pow(h1, p) - std::pow(h2, p)) / (std::pow(h2, p) - std::pow(h3, p)) - ratio; };
  double lo = 0.05, hi = 8;
  if (f(lo) * f(hi) > 0) return std::nullopt;
  for (int i = 0; i < 100; ++i) {
    const double mid = (lo + hi) / 2;
    (f(lo) * f(mid) <= 0 ? hi : lo) = mid;
  }
  return (lo + hi) / 2;
}

// the materials: the continuum at three Poisson's ratios, the spring mesh with and without its diagonals;
// `springs` gets the spring mesh's own
Table poisson_table(UniaxialStretch& springs) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Table poisson{{"model", "nu_set", "nu_measured", "E_set", "E_measured", "strain", "newton_iterations"}, {}};
  const double E = strip_E;
  for (const double nu : {0.0, 0.3, 0.45}) {
    const UniaxialStretch s = uniaxial_stretch({{"continuum", 1}, {"nu", nu}, {"E", E}}, strip_rows, stretch);
    if (!s.failure.empty()) throw std::runtime_error(fmt::format("continuum-cloth: the strip at nu = {}: {}", nu, s.failure));
    poisson.rows.push_back({std::string("continuum"), nu, s.nu, E, s.E, stretch, long{s.iterations}});
  }
  for (const auto& [name, shear] : {std::pair{"springs", 1.0}, std::pair{"springs-no-shear", 0.0}}) {
    const UniaxialStretch s = uniaxial_stretch({{"continuum", 0}, {"shear", shear}}, strip_rows, stretch);
    if (!s.failure.empty()) throw std::runtime_error(fmt::format("continuum-cloth: the {} strip: {}", name, s.failure));
    poisson.rows.push_back({std::string(name), nan, s.nu, nan, s.E, stretch, long{s.iterations}});
    if (shear == 1.0) springs = s;
  }

  return poisson;
}

// "the sides shrink inside": the continuum's hanging sheet at three Poisson's ratios (at the springs' modulus),
// beside the springs'
Table sides_table(double E_springs, int sides_side) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Table narrowing{{"model", "nu", "side", "middle_width", "bottom_width", "sag"}, {}};
  for (const double nu : {0.0, 0.3, 0.45}) {
    const HangingSheet h = hanging_sheet({{"continuum", 1}, {"nu", nu}, {"E", E_springs}}, sides_side);
    if (!h.failure.empty()) throw std::runtime_error(fmt::format("continuum-cloth: the hanging continuum at nu = {}: {}", nu, h.failure));
    narrowing.rows.push_back({std::string("continuum"), nu, long{sides_side}, h.middle_width, h.bottom_width, h.sag});
  }
  // (without its diagonals the spring sheet has no shear stiffness: hanging, it is a mechanism, with no equilibrium)
  const HangingSheet hanging_springs = hanging_sheet({{"continuum", 0}}, sides_side);
  if (!hanging_springs.failure.empty()) throw std::runtime_error(fmt::format("continuum-cloth: the hanging springs: {}", hanging_springs.failure));
  narrowing.rows.push_back({std::string("springs"), nan, long{sides_side}, hanging_springs.middle_width, hanging_springs.bottom_width, hanging_springs.sag});
  return narrowing;
}

// the refinement table's figure: sag and bottom width by mesh, a line a model
std::string refinement_figure(std::vector<Figure>& figures) {
  const auto by_model = [](std::string y) {
    return std::vector<FigureSpec::Layer>{{.table = "continuum_cloth_refinement", .x = "side", .y = std::move(y), .series = "model"}};
  };
  FigureSpec spec{.title = "The hanging sheet as each mesh is refined",
                  .panels = {{.title = "Sag of the top edge", .x_label = "nodes a side", .y_label = "sag (m)", .log_x = true, .layers = by_model("sag")},
                             {.title = "Bottom width (1 m at rest)",
                              .x_label = "nodes a side",
                              .y_label = "bottom width (m)",
                              .log_x = true,
                              .layers = by_model("bottom_width")}}};
  return add_figure(figures, "continuum_cloth", "", std::move(spec), "Springs and the continuum of the same material, hanging, by mesh");
}

// a sheet at rest by mesh: springs (the flag's constants, unscaled) and the continuum of the material the springs
// measured as, each side of `sides`, measured by `sheet`; in the order springs' sides, then the continuum's
struct MeshPoint {
  std::string model;
  int side;
};
template <class Sheet>
std::vector<Sheet> sheets_by_mesh(const StudyContext& ctx, const UniaxialStretch& springs, const std::vector<int>& sides, const char* what,
                                  Sheet (*sheet)(Params, int), std::vector<MeshPoint>& points) {
  points.clear();
  for (const char* model : {"springs", "continuum"})
    for (const int side : sides) points.push_back({model, side});
  std::vector<std::string> labels;
  for (const auto& p : points) labels.push_back(fmt::format("continuum-cloth {} {} {}x{}", what, p.model, p.side, p.side));
  auto sheets = ctx.sweep<Sheet>(labels, [&](size_t i) {
    return sheet(points[i].model == "springs" ? Params{{"continuum", 0}} : continuum_of(springs), points[i].side);
  });
  for (size_t i = 0; i < points.size(); ++i)
    if (!sheets[i].failure.empty()) throw std::runtime_error(fmt::format("continuum-cloth: {}: {}", labels[i], sheets[i].failure));
  return sheets;
}

// refinement: the sheet hanging from its two top corners by mesh; `sides` gets the meshes' sides
Table refinement_table(const StudyContext& ctx, const UniaxialStretch& springs, std::vector<int>& sides) {
  sides = {8, 16, 32};
  if (!ctx.quick) sides.push_back(64);
  Table refinement{{"model", "side", "nodes", "spacing", "sag", "bottom_width", "middle_width", "bottom_drop", "newton_iterations"}, {}};
  std::vector<MeshPoint> points;
  const auto sheets = sheets_by_mesh<HangingSheet>(ctx, springs, sides, "two-point", hanging_sheet, points);
  for (size_t i = 0; i < points.size(); ++i) {
    const HangingSheet& s = sheets[i];
    refinement.rows.push_back({points[i].model, long{points[i].side}, long{points[i].side * points[i].side}, 1.0 / (points[i].side - 1), s.sag,
                               s.bottom_width, s.middle_width, s.bottom_drop, long{s.iterations}});
  }
  return refinement;
}

// the well-posed refinement: the sheet held along its whole top edge, by mesh (8^2 to 32^2, 64^2 in full); the
// continuum's order in the drop, and how far the springs' finest is from the continuum of its own material, in
// percent and in pixels of the flag's frame
struct ClampedRefinement {
  Table table;
  std::string md;
};
ClampedRefinement clamped_refinement(const StudyContext& ctx, const UniaxialStretch& springs) {
  std::vector<int> sides{8, 16, 32};
  if (!ctx.quick) sides.push_back(64);
  ClampedRefinement out;
  out.table = {{"model", "side", "nodes", "drop", "bottom_width", "middle_width"}, {}};
  std::vector<MeshPoint> points;
  const auto sheets = sheets_by_mesh<ClampedSheet>(ctx, springs, sides, "held along its top edge", clamped_sheet, points);
  for (size_t i = 0; i < points.size(); ++i)
    out.table.rows.push_back({points[i].model, long{points[i].side}, long{points[i].side * points[i].side}, sheets[i].drop, sheets[i].bottom_width,
                              sheets[i].middle_width});
  const size_t m = sides.size();  // the continuum's rows follow the springs'
  const auto drop = [&](const std::string& model, size_t k) { return sheets[(model == "springs" ? 0 : m) + k].drop; };
  const auto order = [&](const std::string& model) {
    return observed_order(1.0 / (sides[m - 3] - 1), 1.0 / (sides[m - 2] - 1), 1.0 / (sides[m - 1] - 1), drop(model, m - 3), drop(model, m - 2),
                          drop(model, m - 1));
  };
  const auto shown_order = [](std::optional<double> p) { return p ? fmt::format("{:.2f}", *p) : std::string("none (not monotone)"); };
  const double pixel = flag_frame_extent / frame_pixels;
  const double gap = drop("springs", m - 1) - drop("continuum", m - 1);
  out.md = fmt::format(
      "**Held along its whole top edge, both meshes converge**: the bottom edge's drop under gravity (in its plane) converges "
      "at order {} for the finite elements and {} for the springs ({}², {}², {}²); at {}² the spring sheet drops {:+.1f}% "
      "off the continuum of its own measured material, {:+.2g} mm, {:.2g} px of the flag's {:g}-pixel frame. Hung from two points "
      "instead (below), plane elasticity is singular at the pins and neither converges.\n\n",
      shown_order(order("continuum")), shown_order(order("springs")), sides[m - 3], sides[m - 2], sides[m - 1], sides[m - 1],
      100 * (drop("springs", m - 1) / drop("continuum", m - 1) - 1), 1e3 * gap, std::abs(gap) / pixel, frame_pixels);
  out.md += markdown_table(out.table, {{"model", "model"},
                                       {"side", "nodes a side"},
                                       {"drop", "bottom drop (m)", shown_as("{:.6f}")},
                                       {"bottom_width", "bottom width (m)", shown_as("{:.6f}")},
                                       {"middle_width", "width halfway down (m)", shown_as("{:.6f}")}});
  out.md += "\n";
  return out;
}

// bending against Kirchhoff's plate: the aluminium plate clamped along an edge four spans long (bending_plate), its free
// edge's middle by mesh (9 to 33 nodes along the span, 65 in full) against the plate strip's q L^4 / (8 D); the order,
// the extrapolated ratio, and the square plate beside it (its free side edges curl: anticlastic bending)
struct BendingRefinement {
  Table table;
  std::string md;
};
BendingRefinement bending_refinement(const StudyContext& ctx) {
  std::vector<int> sides{9, 17, 33};
  if (!ctx.quick) sides.push_back(65);
  const size_t m = sides.size();
  std::vector<std::string> labels;
  for (const int side : sides) labels.push_back(fmt::format("continuum-cloth clamped plate {} nodes along the span", side));
  for (const int side : {sides[m - 2], sides[m - 1]}) labels.push_back(fmt::format("continuum-cloth clamped square plate {}x{}", side, side));
  const Params plate = bending_plate();
  const auto strips = ctx.sweep<BentStrip>(labels, [&](size_t i) {
    return i < m ? bent_strip(plate, sides[i], bending_plate_aspect) : bent_strip(plate, sides[m - 2 + (i - m)], 1);
  });
  for (size_t i = 0; i < strips.size(); ++i)
    if (!strips[i].failure.empty()) throw std::runtime_error(fmt::format("continuum-cloth: {}: {}", labels[i], strips[i].failure));
  BendingRefinement out;
  out.table = {{"side", "nodes", "E", "nu", "thickness", "density", "length", "tip_deflection", "analytic"}, {}};
  for (size_t i = 0; i < m; ++i) {
    const long rows = std::lround(bending_plate_aspect * (sides[i] - 1)) + 1;
    out.table.rows.push_back({long{sides[i]}, rows * sides[i], plate.at("E"), plate.at("nu"), plate.at("thickness"), plate.at("density"),
                              strips[i].length, strips[i].tip_deflection, strips[i].analytic});
  }
  const auto ratio = [&](size_t i) { return strips[i].tip_deflection / strips[i].analytic; };
  const std::optional<double> order = observed_order(1.0 / (sides[m - 3] - 1), 1.0 / (sides[m - 2] - 1), 1.0 / (sides[m - 1] - 1), ratio(m - 3),
                                                     ratio(m - 2), ratio(m - 1));
  // Richardson at the observed order (first where none is seen), from the two finest meshes, the spacing nearly halved
  const auto extrapolated = [&](double coarse, double fine, double h_coarse, double h_fine) {
    const double p = order.value_or(1), r = std::pow(h_coarse / h_fine, p);
    return (r * fine - coarse) / (r - 1);
  };
  const double h2 = 1.0 / (sides[m - 2] - 1), h3 = 1.0 / (sides[m - 1] - 1);
  const double strip = extrapolated(ratio(m - 2), ratio(m - 1), h2, h3), square = extrapolated(ratio(m), ratio(m + 1), h2, h3);
  out.md = fmt::format(
      "**Bending is Kirchhoff's plate.** An aluminium plate (E = {:.3g} Pa, ν = {:.2f}, {:g} cm thick), clamped along an edge "
      "{:g} spans long, bends under its own weight; the middle of its free edge converges at order {} to the plate strip's "
      "q L⁴ / (8 D), D = E t³ / (12 (1 − ν²)): extrapolated from {} and {} nodes along the span it is {:.3f} of it. The square "
      "plate bends {:.3f} of it: its free side edges curl across themselves (anticlastic bending), softening it toward the "
      "narrow beam's E t³ / 12 ({:.3f}).\n\n",
      plate.at("E"), plate.at("nu"), 100 * plate.at("thickness"), bending_plate_aspect,
      order ? fmt::format("{:.2f}", *order) : std::string("none (not monotone)"), sides[m - 2], sides[m - 1], strip, square,
      1 / (1 - plate.at("nu") * plate.at("nu")));
  out.md += markdown_table(out.table, {{"side", "nodes along the span"},
                                       {"nodes", "nodes"},
                                       {"length", "span L (m)", shown_as("{:.4f}")},
                                       {"tip_deflection", "tip deflection (m)", shown_as("{:.6f}")},
                                       {"analytic", "q L⁴ / (8 D) (m)", shown_as("{:.6f}")}});
  out.md += "\n";
  return out;
}

// the flag in motion: the seeds' gusting 32 x 32 flag with springs and with the continuum of the springs' own
// material (its measured E and nu), each by implicit Euler at frame-sized steps and below, and the springs by rk4
// far below their explicit limit (their answer converged in time: the model's own offset), every one against the
// continuum's converged run (rk4 far below its limit, checked against itself at twice the step)
struct FlagRun {
  std::string model;
  std::string method;
  double dt;
  int substeps = 1;  // xpbd's
};

// the frames the offsets are read at (a node's largest offset over them: one instant of a billowing flag is
// lucky or not), and the reference's step, 200 a frame; every step of the study divides the frame
constexpr double flag_frame = 1.0 / 15;
constexpr double flag_reference_dt = flag_frame / 200;

struct EqualCpu {
  Table table;
  Table newton;  // backward Euler by Newton on the incremental potential at frame steps (continuum_cloth_newton.csv)
  double reference_pixels = 0;  // the reference's own offset (Richardson, from its run at twice the step)
  double t_end = 0;
};

// the offset of `model` at CPU cost `cpu` (s per simulated s), interpolated log-log between its implicit Euler
// points bracketing it; NaN outside them
double pixels_at_cpu(const Table& table, const std::string& model, double cpu) {
  std::vector<std::pair<double, double>> points;
  for (const auto& row : table.rows)
    if (std::get<std::string>(cell_of(table, row, "model")) == model && std::get<std::string>(cell_of(table, row, "method")) == "implicit-euler")
      points.emplace_back(std::get<double>(cell_of(table, row, "cpu_per_simulated_second")), std::get<double>(cell_of(table, row, "pixels_off")));
  std::sort(points.begin(), points.end());
  for (size_t k = 0; k + 1 < points.size(); ++k) {
    const auto [c0, p0] = points[k];
    const auto [c1, p1] = points[k + 1];
    if (cpu < c0 || cpu > c1 || !(p0 > 0) || !(p1 > 0)) continue;
    const double w = std::log(cpu / c0) / std::log(c1 / c0);
    return std::exp((1 - w) * std::log(p0) + w * std::log(p1));
  }
  return std::numeric_limits<double>::quiet_NaN();
}

std::string setting_of(const FlagRun& r) {
  return r.method == "xpbd" ? fmt::format("dt {:.3g}, {} substeps", r.dt, r.substeps) : fmt::format("dt {:.3g}", r.dt);
}

EqualCpu equal_cpu_table(const StudyContext& ctx, const Params& continuum) {
  const double t_end = ctx.quick ? 0.25 : 1.0;
  std::vector<double> dts{1.0 / 15, 1.0 / 30, 1.0 / 60, 1.0 / 120};
  if (!ctx.quick) dts.push_back(1.0 / 240);
  // (the springs undamped too: the continuum has no damping of its own, the springs' Voigt damping is part of their model)
  std::vector<FlagRun> runs{{"continuum", "rk4", flag_reference_dt},
                            {"continuum", "rk4", 2 * flag_reference_dt},
                            {"springs", "rk4", 2 * flag_reference_dt},
                            {"springs-undamped", "rk4", 2 * flag_reference_dt}};
  for (const char* model : {"springs", "continuum"})
    for (const double dt : dts) runs.push_back({model, "implicit-euler", dt});
  // backward Euler itself at an animator's frame steps; the springs by the engines' methods too
  for (const char* model : {"springs", "continuum"})
    for (const double dt : ctx.quick ? std::vector<double>{1.0 / 60} : std::vector<double>{1.0 / 30, 1.0 / 60, 1.0 / 120})
      runs.push_back({model, "implicit-euler-newton", dt});
  for (const double dt : {1.0 / 60, 1.0 / 120, 1.0 / 240}) runs.push_back({"springs", "fast-mass-spring", dt});
  for (const int substeps : {5, 20, 80}) runs.push_back({"springs", "xpbd", 1.0 / 60, substeps});
  std::vector<std::string> labels;
  std::vector<double> costs;  // ns, measured on this flag: an rk4 step ~0.5 ms (continuum) or 0.25 ms, an implicit step ~10 ms
  for (const auto& r : runs) {
    labels.push_back(fmt::format("continuum-cloth flag {} {} {}", r.model, r.method, setting_of(r)));
    const double step_ns = r.method == "rk4" ? (r.model == "continuum" ? 5e5 : 2.5e5)
                            : r.method == "implicit-euler-newton" ? 4e7
                            : r.method == "xpbd" ? 2e5 * r.substeps : 1e7;
    costs.push_back(t_end / r.dt * step_ns);
  }
  const auto measured = ctx.sweep<Measured>(labels, [&](size_t i) {
    const auto model = make_model("cloth", runs[i].model == "continuum" ? continuum : runs[i].model == "springs" ? Params{} : Params{{"damping", 0}});
    StepControl control = StepControl::fixed(runs[i].dt);
    if (runs[i].method == "xpbd") {
      control.settings["substeps"] = runs[i].substeps;
      control.settings["iterations"] = 1;  // xpbd's small steps: one sweep a substep
    }
    control.observe = [](const Eigen::VectorXd& y) { return y; };  // the whole state at each frame, not the model's summary
    return run_and_measure(*model, runs[i].method, control, t_end, flag_frame);
  }, costs);
  for (size_t i = 0; i < 2; ++i)
    if (measured[i].result.status != Status::ok)
      throw std::runtime_error(fmt::format("continuum-cloth: the flag's reference run failed: {}", measured[i].result.message));
  const Eigen::Index positions = make_model("cloth", {})->as<SecondOrderView>()->positions;
  const double pixel = flag_frame_extent / frame_pixels;
  // the largest node offset from the reference over the frames, in pixels
  const auto pixels_off = [&](const Trajectory& run, const Trajectory& reference) {
    double largest = 0;
    for (size_t f = 0; f < std::min(run.y.size(), reference.y.size()); ++f)
      for (Eigen::Index i = 0; i < positions; i += 3) largest = std::max(largest, (run.y[f].segment<3>(i) - reference.y[f].segment<3>(i)).norm());
    return largest / pixel;
  };
  const Trajectory& reference = measured[0].result.trajectory;
  EqualCpu out;
  out.t_end = t_end;
  // rk4's error at the finer step, estimated from the two (Richardson: the difference over 2^4 - 1)
  out.reference_pixels = pixels_off(measured[1].result.trajectory, reference) / 15;
  out.table = {{"model", "method", "curve", "setting", "dt", "cpu_per_simulated_second", "pixels_off", "other_model_pixels_at_equal_cpu", "status",
                "model_pixels", "stepping_pixels"},
               {}};
  // each offset's two parts: the model's (its own converged run against the continuum's: the springs' rk4 far below
  // their limit, or none for the continuum) and the stepping's (the run against its own model's converged run)
  const Trajectory& springs_converged = measured[2].result.trajectory;
  const double springs_model_pixels = pixels_off(springs_converged, reference);
  out.newton = {{"model", "nu", "dt", "status", "t_stop", "newton_iterations_mean", "line_search_halvings_mean", "cpu_per_simulated_second",
                 "pixels_vs_converged"},
                {}};
  for (size_t i = 2; i < runs.size(); ++i) {
    const RunResult& r = measured[i].result;
    const bool ok = r.status == Status::ok;
    const double pixels = ok ? pixels_off(r.trajectory, reference) : NAN;
    const bool springs = runs[i].model == "springs";
    out.table.rows.push_back({runs[i].model, runs[i].method, fmt::format("{}, {}", runs[i].model, runs[i].method), setting_of(runs[i]), runs[i].dt,
                              r.stats.cpu_seconds / t_end, pixels, NAN, std::string(to_string(r.status)),
                              springs ? springs_model_pixels : runs[i].model == "continuum" ? 0.0 : NAN,
                              !ok ? NAN : springs ? pixels_off(r.trajectory, springs_converged) : runs[i].model == "continuum" ? pixels : NAN});
    if (runs[i].method != "implicit-euler-newton") continue;
    const double steps = static_cast<double>(std::max(1L, r.stats.steps));
    out.newton.rows.push_back({runs[i].model, runs[i].model == "continuum" ? continuum.at("nu") : NAN, runs[i].dt, std::string(to_string(r.status)),
                               ok ? t_end : r.t_stop, static_cast<double>(r.stats.newton_iterations) / steps,
                               static_cast<double>(r.stats.line_search_halvings) / steps, r.stats.cpu_seconds / t_end, pixels});
  }
  const auto& columns = out.table.columns;
  const auto other_column = static_cast<size_t>(std::find(columns.begin(), columns.end(), "other_model_pixels_at_equal_cpu") - columns.begin());
  for (auto& row : out.table.rows) {
    if (std::get<std::string>(cell_of(out.table, row, "method")) != "implicit-euler") continue;
    const std::string other = std::get<std::string>(cell_of(out.table, row, "model")) == "springs" ? "continuum" : "springs";
    row[other_column] = pixels_at_cpu(out.table, other, std::get<double>(cell_of(out.table, row, "cpu_per_simulated_second")));
  }
  return out;
}

// backward Euler itself at frame steps: whether every step converged, its Newton iterations, and what the
// linearised step (Baraff & Witkin's one Newton iteration) adds to the offset at the same step
std::string newton_text(const EqualCpu& motion) {
  const Table& t = motion.table;
  const auto pixels = [&](const std::string& model, const std::string& method, double dt) {
    for (const auto& row : t.rows)
      if (std::get<std::string>(cell_of(t, row, "model")) == model && std::get<std::string>(cell_of(t, row, "method")) == method &&
          std::abs(std::get<double>(cell_of(t, row, "dt")) / dt - 1) < 1e-9)
        return std::get<double>(cell_of(t, row, "pixels_off"));
    return std::numeric_limits<double>::quiet_NaN();
  };
  const auto nearer = [](double difference) { return fmt::format("{:.1f} px {}", std::abs(difference), difference < 0 ? "nearer" : "farther"); };
  long failed = 0;
  std::vector<std::string> steps;  // the frame steps run, "1/30 s" (the quick report runs 1/60 s only)
  for (const auto& row : motion.newton.rows) {
    failed += std::get<std::string>(cell_of(motion.newton, row, "status")) != "ok";
    if (const std::string step = fmt::format("1/{:.0f}", 1 / std::get<double>(cell_of(motion.newton, row, "dt")));
        std::find(steps.begin(), steps.end(), step) == steps.end())
      steps.push_back(step);
  }
  const std::string steps_run = steps.size() > 1 ? fmt::format("{} and {} s", fmt::join(steps.begin(), steps.end() - 1, ", "), steps.back())
                                                 : fmt::format("{} s", steps.empty() ? std::string("no") : steps.front());
  std::string md = fmt::format(
      "**Backward Euler itself, as the minimisation of its incremental potential** (`implicit-euler-newton`: Newton with the exact "
      "Hessian where it is positive definite, else the mass term raised, a line search on the potential), {} the flag at {}, "
      "springs and continuum. Against the same reference the linearised step at 1/60 s is {} (springs) and {} "
      "(continuum) than backward Euler at that step.\n\n",
      failed == 0 ? "converges at every step of" : fmt::format("fails {} of the runs of", failed), steps_run, nearer(pixels("springs", "implicit-euler", 1.0 / 60) - pixels("springs", "implicit-euler-newton", 1.0 / 60)),
      nearer(pixels("continuum", "implicit-euler", 1.0 / 60) - pixels("continuum", "implicit-euler-newton", 1.0 / 60)));
  md += markdown_table(motion.newton, {{"model", "model"},
                                       {"dt", "step (s)", shown_as("{:.4g}")},
                                       {"status", "status"},
                                       {"newton_iterations_mean", "Newton iterations a step", shown_as("{:.2f}")},
                                       {"line_search_halvings_mean", "halvings a step", shown_as("{:.3f}")},
                                       {"cpu_per_simulated_second", "CPU s per simulated s", shown_as("{:.3g}")},
                                       {"pixels_vs_converged", "offset (px)", shown_as("{:.3g}")}});
  return md + "\n";
}

// the flag in motion, in words, its table and its figure
std::string equal_cpu_text(const EqualCpu& motion, const UniaxialStretch& springs, const Params& flag, std::vector<Figure>& figures) {
  const Table& t = motion.table;
  const auto row_of = [&](const std::string& model, const std::string& method, double dt) -> const std::vector<Cell>* {
    for (const auto& row : t.rows)
      if (std::get<std::string>(cell_of(t, row, "model")) == model && std::get<std::string>(cell_of(t, row, "method")) == method &&
          std::abs(std::get<double>(cell_of(t, row, "dt")) / dt - 1) < 1e-9)
        return &row;
    return nullptr;
  };
  const auto value = [&](const std::vector<Cell>* row, const char* column) { return row ? std::get<double>(cell_of(t, *row, column)) : NAN; };
  const auto* frame = row_of("springs", "implicit-euler", 1.0 / 60);
  const auto* converged = row_of("springs", "rk4", 2 * flag_reference_dt);
  const auto* continuum_frame = row_of("continuum", "implicit-euler", 1.0 / 60);
  const double floor_px = value(converged, "pixels_off");
  const double undamped_px = value(row_of("springs-undamped", "rk4", 2 * flag_reference_dt), "pixels_off");
  const double springs_px = value(frame, "pixels_off"), continuum_px = value(frame, "other_model_pixels_at_equal_cpu");
  const std::string closer = !(std::isfinite(springs_px) && std::isfinite(continuum_px)) ? "one of the two not measured at that CPU"
                             : std::abs(springs_px - continuum_px) <= 0.25 * std::max(springs_px, continuum_px)
                                 ? "about as far off either way"
                                 : (springs_px < continuum_px ? "the springs the closer" : "the continuum the closer");
  const std::string verdict =
      std::min(springs_px, continuum_px) >= 0.8 * floor_px
          ? "At an animator's step the integrator's error is as large as the model's: the spring mesh's pseudo-physics shows once "
            "both are converged in time."
          : continuum_px < springs_px ? "At an animator's step the continuum is the closer for the same CPU: the model's error is the larger."
                                      : "At an animator's step the springs are the closer for the same CPU.";
  const std::string damping = std::abs(undamped_px - floor_px) <= 0.25 * floor_px ? "their damping is not the difference" : "their damping is part of it";
  std::string md = fmt::format(
      "**In motion, the spring flag converged in time stays {:.0f} pixels from the continuum of its own material ({:.0f} undamped: "
      "{}); at equal CPU with implicit Euler, the springs at 1/60 s are {:.0f} px off and the continuum at the same CPU {:.0f} px: "
      "{}.** {} The seeds' gusting flag ({:g} × {:g} nodes, over {:g} s) with springs and with the continuum of the springs' "
      "measured material (E = {:.3g} Pa, ν = {:.3f}; its bending that of the {:g} mm sheet), each by implicit Euler at steps of "
      "1/15 s and below, and the springs by rk4 at 1/{:.0f} s (converged in time), against the continuum's converged run (rk4 at "
      "1/{:.0f} s; its own error, from the run at twice the step, {:.2g} px). An offset is the farthest any node is from the "
      "reference's at the frames (every 1/{:.0f} s), in pixels of a {:.0f}-pixel frame {:g} m tall; the other model at equal CPU "
      "is interpolated between its steps. The continuum is damped by its own viscous stress at the springs' rate (Rayleigh's β = γ / c "
      "= {:.2g} s, the springs' Voigt damping read as a material's); implicit Euler on it is {:.0f} px off at 1/60 s, {:.2f} CPU s per "
      "simulated s. **At 1/60 s the spring mesh by backward Euler is {:.0f} px from the material it imitates; the model alone (the "
      "springs converged in time) is {:.0f} px from it, and the stepping alone (the run against the springs' own converged run) "
      "{:.0f} px** (largest offsets over the frames: the two parts do not add).\n\n",
      floor_px, undamped_px, damping, springs_px, continuum_px, closer, verdict, flag.at("rows"), flag.at("columns"), motion.t_end, springs.E,
      continuum_of(springs).at("nu"), 1e3 * flag.at("thickness"), 1 / (2 * flag_reference_dt), 1 / flag_reference_dt, motion.reference_pixels,
      1 / flag_frame, frame_pixels, flag_frame_extent, flag.at("damping") / flag.at("stiffness"), value(continuum_frame, "pixels_off"),
      value(continuum_frame, "cpu_per_simulated_second"), value(row_of("springs", "implicit-euler-newton", 1.0 / 60), "pixels_off"),
      value(row_of("springs", "implicit-euler-newton", 1.0 / 60), "model_pixels"), value(row_of("springs", "implicit-euler-newton", 1.0 / 60), "stepping_pixels"));
  FigureSpec spec{.title = fmt::format("The flag over {:g} s against the converged continuum", motion.t_end),
                  .panels = {{.x_label = "CPU seconds per simulated second",
                              .y_label = "largest node offset (pixels of 720)",
                              .log_x = true,
                              .log_y = true,
                              .layers = {{.table = "continuum_cloth_equal_cpu",
                                          .x = "cpu_per_simulated_second",
                                          .y = "pixels_off",
                                          .series = "curve",
                                          .hover = {{"setting", "setting"}}}}}}};
  md += add_figure(figures, "continuum_cloth_equal_cpu", "", std::move(spec), "The flag, springs and continuum: offset against CPU time");
  md += markdown_table(t, {{"model", "model"},
                           {"method", "method"},
                           {"setting", "step"},
                           {"cpu_per_simulated_second", "CPU s per simulated s", shown_as("{:.3g}")},
                           {"pixels_off", "offset (px)", shown_as("{:.3g}")},
                           {"model_pixels", "of it the model's (px)", shown_as("{:.3g}")},
                           {"stepping_pixels", "the stepping's (px)", shown_as("{:.3g}")},
                           {"other_model_pixels_at_equal_cpu", "the other model at this CPU (px)", shown_as("{:.3g}")},
                           {"status", "status"}});
  return md + "\n";
}

StudyOutput continuum_cloth(const StudyContext& ctx) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  UniaxialStretch springs_measured;
  Table poisson = poisson_table(springs_measured);
  const UniaxialStretch* springs = &springs_measured;
  std::vector<int> sides;
  const Table refinement = refinement_table(ctx, *springs, sides);
  const auto value = [&](const std::string& model, int side, const char* column) {
    for (const auto& row : refinement.rows)
      if (std::get<std::string>(cell_of(refinement, row, "model")) == model && std::get<long>(cell_of(refinement, row, "side")) == side)
        return std::get<double>(cell_of(refinement, row, column));
    return nan;
  };
  const int n3 = sides.back(), n2 = sides[sides.size() - 2], n1 = sides[sides.size() - 3];
  const auto order = [&](const std::string& model, const char* column) {
    return observed_order(1.0 / (n1 - 1), 1.0 / (n2 - 1), 1.0 / (n3 - 1), value(model, n1, column), value(model, n2, column), value(model, n3, column));
  };
  // the last doubling's growth of the sag over the one before
  const auto growth_ratio = [&](const std::string& model) {
    return (value(model, n3, "sag") - value(model, n2, "sag")) / (value(model, n2, "sag") - value(model, n1, "sag"));
  };
  const auto shown_order = [](std::optional<double> p) { return p ? fmt::format("{:.2f}", *p) : std::string("none (not monotone)"); };
  const double gap_sag = value("springs", n3, "sag") / value("continuum", n3, "sag") - 1;
  const double gap_width = value("springs", n3, "bottom_width") / value("continuum", n3, "bottom_width") - 1;
  const int sides_side = 32;
  const Table narrowing = sides_table(springs->E, sides_side);
  const auto widening_of = [&](const std::string& model, double nu) {
    for (const auto& row : narrowing.rows) {
      const double row_nu = std::get<double>(cell_of(narrowing, row, "nu"));
      if (std::get<std::string>(cell_of(narrowing, row, "model")) == model && (std::isnan(nu) ? std::isnan(row_nu) : row_nu == nu))
        return std::get<double>(cell_of(narrowing, row, "middle_width")) - 1;
    }
    return nan;
  };
  const double no_shear_nu = [&] {
    for (const auto& row : poisson.rows)
      if (std::get<std::string>(cell_of(poisson, row, "model")) == "springs-no-shear") return std::get<double>(cell_of(poisson, row, "nu_measured"));
    return nan;
  }();

  const Params flag = resolve_params(*find_model("cloth"), {});  // the seeds' flag: the model's defaults
  std::string md = fmt::format(
      "**The spring mesh is an elastic material with Poisson's ratio {:.3f} and Young's modulus {:.3g} Pa** (the flag's "
      "constants, {:g}, {:g} and {:g} N/m, read as a {:g} mm sheet), measured as the finite elements are, on a strip stretched "
      "{:.1f}%; without its diagonal (shear) springs its ratio is {:.3f}. The seed's \"volume preservation\" by the diagonals is "
      "that Poisson's ratio (without them the hanging sheet, which has then no shear stiffness, is a mechanism): but hanging "
      "from its two top corners ({}², in its plane) the sheet does not shrink inside: its width halfway down changes by {:+.2f} mm "
      "(springs), and by {:+.2f}, {:+.2f} and {:+.2f} mm for the continuum of the springs' modulus at ν = 0, 0.3 and 0.45 (only "
      "a nearly incompressible sheet draws in: the weight hung from two points spreads the sheet sideways as it stretches it "
      "down). **Neither mesh converges fast**: the sheet hangs from two points, where the continuum's stress is singular, and its "
      "sag grows with every refinement, each doubling's growth {:.2f} of the last one's for the finite elements (order {} from "
      "{}², {}², {}²) and {:.2f} for the springs (order {}); at {}² the spring sheet's sag is {:+.1f}% off the continuum of its own material "
      "and its bottom width {:+.2f}%.\n\n",
      springs->nu, springs->E, flag.at("stiffness"), flag.at("shear_stiffness"), flag.at("bend_stiffness"), 1e3 * flag.at("thickness"),
      100 * stretch, no_shear_nu, sides_side, 1e3 * widening_of("springs", nan),
      1e3 * widening_of("continuum", 0.0), 1e3 * widening_of("continuum", 0.3), 1e3 * widening_of("continuum", 0.45),
      growth_ratio("continuum"), shown_order(order("continuum", "sag")), n1, n2, n3, growth_ratio("springs"), shown_order(order("springs", "sag")),
      n3, 100 * gap_sag, 100 * gap_width);
  md += fmt::format(
      "Each is a static equilibrium in the sheet's plane (`solvers/static_equilibrium`: Newton on CHOLMOD with the elements' "
      "Hessians projected to positive semidefinite and a backtracking line search; every z held). The strip is 4 × 1 m, {} × {} "
      "nodes, its left end held, its right end moved by the strain, free to narrow; ν is minus the lateral strain at its middle "
      "over the strain, E the pull per unit width over thickness × strain. The continuum's ν and E are the material's to "
      "{:.2g} and {:.2g} of themselves at ν = 0.3 (test_membrane holds them to 1%).\n\n",
      strip_rows, 4 * (strip_rows - 1) + 1, [&] {
        for (const auto& row : poisson.rows)
          if (std::get<std::string>(cell_of(poisson, row, "model")) == "continuum" && std::get<double>(cell_of(poisson, row, "nu_set")) == 0.3)
            return std::abs(std::get<double>(cell_of(poisson, row, "nu_measured")) / 0.3 - 1);
        return nan;
      }(),
      [&] {
        for (const auto& row : poisson.rows)
          if (std::get<std::string>(cell_of(poisson, row, "model")) == "continuum" && std::get<double>(cell_of(poisson, row, "nu_set")) == 0.3)
            return std::abs(std::get<double>(cell_of(poisson, row, "E_measured")) / strip_E - 1);
        return nan;
      }());
  const auto number = [](const char* f) { return shown_as(f); };
  md += markdown_table(poisson, {{"model", "model"},
                                 {"nu_set", "ν set", number("{:.2f}")},
                                 {"nu_measured", "ν measured", number("{:.4f}")},
                                 {"E_set", "E set (Pa)", number("{:.3g}")},
                                 {"E_measured", "E measured (Pa)", number("{:.4g}")},
                                 {"newton_iterations", "Newton iterations"}});
  md += "\nThe hanging sheet (1 m square, 0.5 kg, pinned at its two top corners, gravity in its plane, applied in four steps), "
        "each mesh side by side:\n\n";
  md += markdown_table(refinement, {{"model", "model"},
                                    {"side", "nodes a side"},
                                    {"sag", "sag (m)", number("{:.5f}")},
                                    {"bottom_width", "bottom width (m)", number("{:.5f}")},
                                    {"middle_width", "width halfway down (m)", number("{:.5f}")},
                                    {"bottom_drop", "bottom drop (m)", number("{:.5f}")},
                                    {"newton_iterations", "Newton iterations"}});
  md += fmt::format("\nThe sides drawing in, {}² (the continuum at the springs' modulus):\n\n", sides_side);
  md += markdown_table(narrowing, {{"model", "model"},
                                   {"nu", "ν", number("{:.2f}")},
                                   {"middle_width", "width halfway down (m)", number("{:.5f}")},
                                   {"bottom_width", "bottom width (m)", number("{:.5f}")},
                                   {"sag", "sag (m)", number("{:.5f}")}});
  md += "\n";
  ClampedRefinement clamped = clamped_refinement(ctx, *springs);
  BendingRefinement bending = bending_refinement(ctx);
  md += clamped.md + bending.md;
  std::vector<Figure> figures;
  md += refinement_figure(figures);
  // the continuum damped by its own viscous stress at the springs' rate: a spring's Voigt damping gamma is beta c, so
  // beta = gamma / c with the structural springs' c (the membrane's stiffness is mostly theirs)
  Params damped = continuum_of(*springs);
  damped["rayleigh_beta"] = flag.at("damping") / flag.at("stiffness");
  EqualCpu motion = equal_cpu_table(ctx, damped);
  md += equal_cpu_text(motion, *springs, flag, figures);
  md += newton_text(motion);
  return {{{"continuum_cloth_poisson", std::move(poisson)},
           {"continuum_cloth_refinement", std::move(refinement)},
           {"continuum_cloth_clamped", std::move(clamped.table)},
           {"continuum_cloth_bending", std::move(bending.table)},
           {"continuum_cloth_sides", std::move(narrowing)},
           {"continuum_cloth_equal_cpu", std::move(motion.table)},
           {"continuum_cloth_newton", std::move(motion.newton)}},
          md, figures};
}

}  // namespace

Study continuum_cloth_study() {
  return {"continuum-cloth", "Cloth: the spring mesh against the continuum (finite elements), at rest and in motion", continuum_cloth};
}

}  // namespace stepwise
