// The report's study: cloth: where explicit methods fail against stiffness, implicit Euler's damping, what each spring family adds.
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

// a section of the study: its table and its Markdown
struct Section {
  Table table;
  std::string md;
};

// the explicit methods' limits on the 8 x 8 sheet against its stiffness, measured by bisection and predicted from
// its stiffest mode, and implicit Euler at 100 times symplectic Euler's limit
Section stability_section(const StudyContext& ctx, std::vector<Figure>& figures) {
  const bool quick = ctx.quick;
  const long steps = 2000;
  const std::vector<double> stiffnesses = quick ? std::vector<double>{10, 100, 1000} : std::vector<double>{10, 100, 1000, 10000};
  Table limits{{"stiffness", "method", "omega_max", "mode_damping", "predicted_dt", "measured_dt", "measured_over_predicted"}, {}};
  std::string md = fmt::format(
      "An 8 x 8 sheet (0.5 kg, hanging from two corners; shear and bend springs at 1/2 and 1/10 of the structural stiffness c). "
      "The largest stable dt found by bisection (to 0.1%: {} steps from rest stay within 1e6 of the start), beside the limit "
      "predicted from the stiffest mode of M^-1 K at the start (omega_max, and its damping rate a from the springs' Voigt "
      "damping and the drag) and each method's stability region on x'' = -omega^2 x - 2 a x': symplectic Euler "
      "2 (sqrt(a^2 + omega^2) - a) / omega^2, rk4 where |R(h lambda)| = 1 (2 sqrt 2 / omega undamped), explicit Euler "
      "2 a / omega^2 (stable only through damping). Implicit Euler is run at 100 times symplectic Euler's limit.\n\n",
      steps);
  double worst_symplectic = 0, rk4_low = 10, rk4_high = 0, euler_low = 1e9, euler_high = 0;
  bool implicit_all_ok = true;
  // the bisections, one point per (stiffness, method), and implicit Euler at 100 times symplectic Euler's limit
  // the methods whose limit on a mass-spring mode is derived (the method table's oscillator_dt): the explicit ones,
  // on the CPU (gpu-cloth runs symplectic Euler's scheme in float32)
  const std::vector<std::string> explicit_methods =
      method_names_where([](const Method& m) { return m.source == Source::hand_written && static_cast<bool>(m.stability.oscillator_dt); });
  std::vector<std::string> labels;
  for (const double c : stiffnesses) {
    for (const auto& method : explicit_methods) labels.push_back(fmt::format("c {:g} {}", c, method));
    labels.push_back(fmt::format("c {:g} implicit-euler", c));
  }
  const size_t per_stiffness = explicit_methods.size() + 1;
  const auto found = ctx.sweep<std::pair<StiffestMode, double>>(labels, [&](size_t i) {
    const auto model = stability_sheet(stiffnesses[i / per_stiffness]);
    const StiffestMode mode = stiffest_mode(*model, 0, model->initial_state());
    const size_t k = i % per_stiffness;
    if (k < explicit_methods.size())
      return std::pair{mode, measured_stable_dt(*model, explicit_methods[k], steps, *mass_spring_stable_dt(explicit_methods[k], mode))};
    // implicit Euler's point: 1 if it stayed bounded and lost energy, else 0
    const double dt = 100 * *mass_spring_stable_dt("symplectic-euler", mode);
    const Measured m = run_and_measure(*model, "implicit-euler", StepControl::fixed(dt), 2.0, 2.0);
    const bool ok = m.result.status == Status::ok && *model->energy(m.result.y_stop) < *model->energy(model->initial_state());
    return std::pair{mode, ok ? 1.0 : 0.0};
  });
  for (size_t i = 0; i < labels.size(); ++i) {
    const double c = stiffnesses[i / per_stiffness];
    const auto& [mode, value] = found[i];
    const size_t k = i % per_stiffness;
    if (k == explicit_methods.size()) {
      implicit_all_ok = implicit_all_ok && value == 1.0;
      limits.rows.push_back({c, std::string("implicit-euler"), mode.omega, mode.damping, NAN, 100 * *mass_spring_stable_dt("symplectic-euler", mode), NAN});
      continue;
    }
    const std::string& method = explicit_methods[k];
    const double predicted = *mass_spring_stable_dt(method, mode), measured = value, ratio = measured / predicted;
    limits.rows.push_back({c, method, mode.omega, mode.damping, predicted, measured, ratio});
    if (method == "symplectic-euler") worst_symplectic = std::max(worst_symplectic, std::abs(ratio - 1));
    if (method == "rk4") rk4_low = std::min(rk4_low, ratio), rk4_high = std::max(rk4_high, ratio);
    if (method == "euler") euler_low = std::min(euler_low, ratio), euler_high = std::max(euler_high, ratio);
  }
  // the explicit methods' rows (implicit Euler's say only where it was run)
  md += markdown_table(limits,
                       {{"stiffness", "c (N/m)", shown_as("{}")},
                        {"omega_max", "omega_max (rad/s)", shown_as("{:.1f}")},
                        {"mode_damping", "a (1/s)", shown_as("{:.3g}")},
                        {"method", "method"},
                        {"predicted_dt", "predicted dt (s)", shown_as("{:.4g}")},
                        {"measured_dt", "measured dt (s)", shown_as("{:.4g}")},
                        {"measured_over_predicted", "measured / predicted", shown_as("{:.3f}")}},
                       [&](size_t row) { return std::get<std::string>(limits.rows[row][1]) != "implicit-euler"; });
  md += "\n";
  // the explicit methods' limits (implicit Euler's rows have no prediction: it is stable at every step)
  const auto limit = [](std::string column, std::string label, FigureMark mark) {
    return FigureSpec::Layer{.table = "cloth_stability", .x = "stiffness", .y = std::move(column), .series = "method", .label = std::move(label),
                             .mark = mark, .complete = {"predicted_dt"}};
  };
  FigureSpec stability_spec{.title = "8 x 8 sheet: explicit methods' limits from the stiffest mode",
                            .panels = {{.x_label = "structural stiffness c (N/m)", .y_label = "largest stable dt (s)", .log_x = true, .log_y = true,
                                        .layers = {limit("predicted_dt", "{} predicted", FigureMark::line), limit("measured_dt", "{} measured", FigureMark::points)}}}};
  md += add_figure(figures, "cloth_stability", "", std::move(stability_spec),
                   "Largest stable step against the sheet's stiffness: measured points, predicted lines");
  md += fmt::format(
      "\nSymplectic Euler's measured limit is its predicted one to {:.2f}% at every stiffness: it falls as 1/sqrt(c), three "
      "decades of stiffness costing a factor {:.0f} in step. rk4's measured limit lies {:.1f}-{:.1f}% above its prediction: near its "
      "damped boundary |R| grows so slowly that {} steps do not show it. Explicit Euler's prediction is safe, but the probe finds "
      "it {:.2f}-{:.2f} times too small: its growth per step near the limit, h (h omega^2 - 2a), is tiny, and its limit falls as "
      "1/c, not 1/sqrt(c). Implicit Euler {} at 100 times symplectic Euler's step at every stiffness, its energy below where it "
      "started.\n\n",
      100 * worst_symplectic, std::sqrt(stiffnesses.back() / stiffnesses.front()), 100 * (rk4_low - 1), 100 * (rk4_high - 1), steps,
      euler_low, euler_high, implicit_all_ok ? "stays bounded" : "did NOT stay bounded everywhere");

  return {std::move(limits), md};
}

// implicit Euler's numerical damping on one linear spring: amplitude per step against 1 / sqrt(1 + w^2 h^2)
Section damping_section(std::vector<Figure>& figures) {
  std::string md;
  Table damping{{"omega_h", "measured_ratio", "predicted_ratio", "periods_to_halve"}, {}};
  md += "Implicit Euler's numerical damping: one mass on one undamped spring (w = 20 rad/s), the amplitude sqrt(w^2 u^2 + v^2) "
        "kept per step against 1 / sqrt(1 + w^2 h^2).\n\n";
  std::map<double, double> halving;
  double worst_damping = 0;
  for (const double wh : {0.01, 0.1, 0.5, 1.0, 3.0}) {
    const double ratio = implicit_euler_amplitude_ratios(wh, 1)[0];
    const double predicted = 1 / std::sqrt(1 + wh * wh);
    const double halve = std::log(2) / -std::log(ratio) * wh / (2 * std::numbers::pi);
    damping.rows.push_back({wh, ratio, predicted, halve});
    halving[wh] = halve;
    worst_damping = std::max(worst_damping, std::abs(ratio / predicted - 1));
  }
  md += markdown_table(damping, {{"omega_h", "w h", shown_as("{}")},
                                 {"measured_ratio", "measured", shown_as("{:.12f}")},
                                 {"predicted_ratio", "1 / sqrt(1 + w^2 h^2)", shown_as("{:.12f}")},
                                 {"periods_to_halve", "periods to halve", shown_as("{:.3g}")}});
  md += "\n";
  const auto kept = [](std::string column, std::string label, FigureMark mark) {
    return FigureSpec::Layer{.table = "cloth_implicit_damping", .x = "omega_h", .y = std::move(column), .label = std::move(label), .mark = mark};
  };
  FigureSpec damping_spec{.title = "Implicit Euler's numerical damping of one spring",
                          .panels = {{.x_label = "w h", .y_label = "amplitude kept per step", .log_x = true,
                                      .layers = {kept("predicted_ratio", "1 / sqrt(1 + w^2 h^2)", FigureMark::line),
                                                 kept("measured_ratio", "implicit-euler, measured", FigureMark::points)}}}};
  md += add_figure(figures, "cloth_implicit_damping", "", std::move(damping_spec), "Implicit Euler's amplitude kept per step against w h");
  md += fmt::format(
      "\nThe measured ratio is 1 / sqrt(1 + w^2 h^2) to {:.1e}. A mode at w h = 0.01 (628 steps a period) loses half its amplitude "
      "in {:.3g} periods, at w h = 0.1 (63 steps a period) in {:.3g}; a cloth's stiff in-plane modes (w h >> 1) are gone within a step or two: "
      "implicit Euler is stable there by removing them.\n\n",
      worst_damping, halving[0.01], halving[0.1]);

  return {std::move(damping), md};
}

// what each spring family adds: the sheet hanging from two corners, 16 x 16, 3 s
Section families_section() {
  std::string md;
  Table families{{"structural", "shear", "bend", "y_min", "max_stretch", "cpu_seconds", "status"}, {}};
  md += "What each spring family adds: the 16 x 16 sheet hanging from two corners for 3 s (implicit-euler, dt = 0.01).\n\n";
  std::vector<Eigen::VectorXd> ends;
  for (const auto& [shear, bend] : {std::pair{0, 0}, {1, 0}, {1, 1}}) {
    const auto model = make_model("cloth", {{"rows", 16}, {"columns", 16}, {"pin_corners", 0}, {"pin_top_corners", 1}, {"wind_coefficient", 0},
                                            {"shear", shear}, {"bend", bend}, {"damping", 0.05}, {"drag", 0.1}});
    const Measured m = run_and_measure(*model, "implicit-euler", StepControl::fixed(0.01), 3.0, 3.0);
    const Eigen::VectorXd end = model->summary(m.result.y_stop);
    families.rows.push_back({1.0, static_cast<double>(shear), static_cast<double>(bend), end[5], end[6], m.result.stats.cpu_seconds,
                             std::string(to_string(m.result.status))});
    ends.push_back(end);
  }
  md += markdown_table(families, {{"structural", "structural", shown_as("{:g}")},
                                  {"shear", "shear", shown_as("{:g}")},
                                  {"bend", "bend", shown_as("{:g}")},
                                  {"y_min", "lowest point (m)", shown_as("{:.4f}")},
                                  {"max_stretch", "largest stretch", shown_as("{:.4f}")},
                                  {"cpu_seconds", "CPU (s)", shown_as("{:.3f}")}});
  md += fmt::format(
      "\nStructural springs alone leave the sheet free to shear: adding the shear springs moves its lowest point by {:.3f} m and "
      "its largest stretch from {:.3f} to {:.3f}. The bend springs then move the lowest point by only {:.4f} m: a sheet hanging "
      "in its own plane barely bends, so for this scene they are model it does not need.\n\n",
      ends[1][5] - ends[0][5], ends[0][6], ends[1][6], ends[2][5] - ends[1][5]);

  return {std::move(families), md};
}

// momentum: a free sheet (no pins, gravity, drag or wind) pulled by one corner; its momentum is exactly F t
Section momentum_section(const StudyContext& ctx) {
  std::string md;
  Table momentum{{"method", "dt", "momentum_error", "cpu_seconds", "status"}, {}};
  const Params free_sheet{{"rows", 16}, {"columns", 16}, {"pin_corners", 0}, {"pin_top_corners", 0}, {"g", 0}, {"drag", 0},
                          {"wind_coefficient", 0}, {"pick_row", 0}, {"pick_column", 0}, {"pick_fz", 1}};
  const double pull_time = 1.0;
  const auto sheet = make_model("cloth", free_sheet);
  const StiffestMode sheet_mode = stiffest_mode(*sheet, 0, sheet->initial_state());
  const double explicit_dt = 0.5 * *mass_spring_stable_dt("symplectic-euler", sheet_mode);
  const std::vector<std::pair<std::string, double>> momentum_runs{{"symplectic-euler", explicit_dt}, {"rk4", explicit_dt},
                                                                  {"implicit-euler", 10 * explicit_dt}, {"implicit-euler-newton", 10 * explicit_dt},
                                                                  {"fast-mass-spring", 10 * explicit_dt}};
  std::vector<std::string> momentum_labels;
  for (const auto& [method, dt] : momentum_runs) momentum_labels.push_back("momentum " + method);
  const auto pulled = ctx.sweep<Measured>(momentum_labels, [&](size_t i) {
    const auto model = make_model("cloth", free_sheet);
    return run_and_measure(*model, momentum_runs[i].first, StepControl::fixed(momentum_runs[i].second), pull_time, pull_time);
  });
  md += fmt::format(
      "Momentum: the 16 x 16 sheet floating free (no pins, gravity, drag or wind), pulled by a corner with 1 N along z for {:g} s: its "
      "momentum is exactly F t, whatever the springs do, since their forces cancel in pairs. The error is |P - F t| / |F t|; the explicit "
      "methods run at half symplectic Euler's limit ({:.3g} s), the implicit ones at 10 times that.\n\n",
      pull_time, 2 * explicit_dt);
  const int positions = sheet->as<SecondOrderView>()->positions;
  const double node_mass = sheet->as<MassSpringView>()->mass[0];
  for (size_t i = 0; i < momentum_runs.size(); ++i) {
    const RunResult& r = pulled[i].result;
    const Eigen::VectorXd v = r.y_stop.tail(positions);
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int k = 0; k < positions / 3; ++k) p += node_mass * v.segment<3>(3 * k);
    const double error = r.status == Status::ok ? (p - Eigen::Vector3d(0, 0, pull_time)).norm() / pull_time : NAN;
    momentum.rows.push_back({momentum_runs[i].first, momentum_runs[i].second, error, r.stats.cpu_seconds, std::string(to_string(r.status))});
  }
  md += markdown_table(momentum, {{"method", "method"},
                                  {"dt", "dt (s)", shown_as("{:.3g}")},
                                  {"momentum_error", "momentum error", shown_as("sci")},
                                  {"cpu_seconds", "CPU (s)", shown_as("{:.3f}")}});
  const auto momentum_error = [&](size_t i) { return std::get<double>(momentum.rows[i][2]); };
  md += fmt::format(
      "\nThe springs' forces cancel in pairs in every evaluation, so the explicit methods keep F t to round-off ({} and {}). Implicit "
      "Euler's K and D have zero block-row sums (the springs do not care where the sheet is), so each of its solves adds h F to the "
      "momentum: {} with CG from a kept factor, {} with Newton. Liu's method keeps it to {}: the truncation of its 10 iterations.\n\n",
      sci(momentum_error(0)), sci(momentum_error(1)), sci(momentum_error(2)), sci(momentum_error(3)), sci(momentum_error(4)));
  return {std::move(momentum), md};
}

StudyOutput cloth(const StudyContext& ctx) {
  std::vector<Figure> figures;
  Section stability = stability_section(ctx, figures), damping = damping_section(figures), families = families_section(), momentum = momentum_section(ctx);
  return {{{"cloth_stability", std::move(stability.table)},
           {"cloth_implicit_damping", std::move(damping.table)},
           {"cloth_families", std::move(families.table)},
           {"cloth_momentum", std::move(momentum.table)}},
          stability.md + damping.md + families.md + momentum.md,
          figures};
}

}  // namespace

Study cloth_study() { return {"cloth", "Cloth: explicit methods' limits against stiffness, implicit Euler's damping, the spring families", cloth}; }

}  // namespace stepwise
