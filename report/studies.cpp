#include "studies.hpp"

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

// ---- energy: the pendulum over many periods

StudyOutput energy(const StudyContext& ctx) {
  const bool quick = ctx.quick;
  const int periods = quick ? 100 : 1000;
  const int samples = 20;  // per period: the error oscillates within a period, so one sample a period would alias it
  const double theta0 = 0.5;
  const auto model = make_model("pendulum", {{"theta0", theta0}});
  const double period = pendulum_period(theta0, 9.81, 1.0);
  const double e0 = *model->energy(model->initial_state());
  Table table{{"method", "t", "relative_energy_error"}, {}};
  Table summary{{"method", "max_first_tenth", "max_last_tenth", "at_end"}, {}};
  std::string md = fmt::format("Pendulum at theta0 = {} rad over {} periods, dt = T/100: the largest relative energy error "
                               "|E - E0|/E0 over the first and the last tenth of the run ({} samples a period), and the "
                               "error at the end. A symplectic method keeps it bounded; explicit Euler's grows and "
                               "implicit Euler's decays towards the bottom of the well (-1).\n\n"
                               "| method | max over first tenth | max over last tenth | at the end |\n|---|---|---|---|\n",
                               theta0, periods, samples);
  for (const std::string method : {"euler", "symplectic-euler", "implicit-euler", "rk4"}) {
    StepControl control;
    control.dt = period / 100;
    const Measured m = run_and_measure(*model, method, control, periods * period, period / samples);
    const auto& ys = m.result.trajectory.y;
    std::vector<double> errors;
    for (size_t i = 0; i < ys.size(); ++i) {
      errors.push_back((*model->energy(ys[i]) - e0) / e0);
      table.rows.push_back({method, m.result.trajectory.t[i], errors.back()});
    }
    auto max_abs = [&](size_t begin, size_t end) {
      double v = 0;
      for (size_t i = begin; i < end; ++i) v = std::max(v, std::abs(errors[i]));
      return v;
    };
    const size_t n = errors.size(), tenth = n / 10;
    const double first = max_abs(0, tenth), last = max_abs(n - tenth, n), end = errors.empty() ? NAN : errors.back();
    summary.rows.push_back({method, first, last, end});
    md += fmt::format("| {} | {:.3e} | {:.3e} | {:+.3e} |\n", method, first, last, end);
  }
  std::vector<Figure> figures;
  md += "\n";
  md += add_figure(figures, "energy", "", "Relative energy error of the pendulum over time, per method");
  return {{{"energy", std::move(table)}, {"energy_summary", std::move(summary)}}, md, figures};
}

// ---- adequacy: where the small-angle model stops being enough

StudyOutput adequacy(const StudyContext&) {
  Table table{{"phase_tolerance_rad", "periods", "max_amplitude_rad", "max_amplitude_deg"}, {}};
  std::string md = "Largest amplitude at which the small-angle pendulum (theta'' = -(g/L) theta) stays within a phase "
                   "error of the exact (elliptic) solution after N periods. Below it the linear model, which costs one "
                   "cosine per sample and no integration at all, is all a scene needs.\n\n"
                   "| phase tolerance (rad) | periods | max amplitude (deg) |\n|---|---|---|\n";
  for (const double tolerance : {0.01, 0.1, 1.0})
    for (const double periods : {1.0, 10.0, 100.0}) {
      const double amplitude = small_angle_max_amplitude(tolerance, periods);
      table.rows.push_back({tolerance, periods, amplitude, amplitude * 180 / std::numbers::pi});
      md += fmt::format("| {} | {:.0f} | {:.2f} |\n", tolerance, periods, amplitude * 180 / std::numbers::pi);
    }
  std::vector<Figure> figures;
  md += "\n";
  md += add_figure(figures, "adequacy", "", "Largest amplitude the small-angle pendulum serves, against the periods shown");
  return {{{"adequacy", std::move(table)}}, md, figures};
}

// ---- adequacy: where the linear wave equation stops being enough

StudyOutput wave_adequacy(const StudyContext& context) {
  const std::vector<double> ratios{1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3};
  std::vector<std::string> labels;
  for (const double r : ratios) labels.push_back(fmt::format("A/H = {:g}", r));
  const auto departures = context.sweep<LinearWaveDeparture>(labels, [&](size_t k) { return linear_wave_departure(-ratios[k]); });
  Table table{{"amplitude_over_depth", "relative_departure", "relative_max_departure", "departure_per_amplitude"}, {}};
  const LinearWaveSetup setup;
  std::string md = fmt::format("The height field's wave equation is the shallow water equations linearised (c^2 = g H). Both are "
                               "run from the same dent of depth A in water of depth H = {} m ({} x {} points, d = {} m, a raised "
                               "cosine of radius {} m, mu = {} /s) by rk4 at dt = {} s to t = {} s, as the ring has crossed most of "
                               "the pool; ", setup.depth, setup.size, setup.size, setup.spacing, setup.radius, setup.mu, setup.dt, setup.t_end);
  md += "the table gives the difference of the surfaces relative to the wave equation's. It grows "
                   "in proportion to A / H (the ratio in the last column holds), so the wave equation is within 1% of "
                   "shallow water below A / H = " + fmt::format("{:.3f}", 0.01 * ratios[0] / departures[0].relative) +
                   " and within 10% below " + fmt::format("{:.2f}", 0.1 * ratios[0] / departures[0].relative) +
                   ": ripples on a pond, not waves on a beach.\n\n"
                   "| A / H | \\|eta - z\\| / \\|z\\| | max \\|eta - z\\| / max \\|z\\| | departure / (A / H) |\n|---|---|---|---|\n";
  for (size_t k = 0; k < ratios.size(); ++k) {
    const auto& d = departures[k];
    table.rows.push_back({ratios[k], d.relative, d.relative_max, d.relative / ratios[k]});
    md += fmt::format("| {:g} | {:.3e} | {:.3e} | {:.3f} |\n", ratios[k], d.relative, d.relative_max, d.relative / ratios[k]);
  }
  std::vector<Figure> figures;
  md += "\n";
  md += add_figure(figures, "wave_adequacy", "", "The linear wave equation's departure from shallow water against the drop's depth over the water's");
  return {{{"wave_adequacy", std::move(table)}}, md, figures};
}

// ---- the seeds' animated bouncing ball against the physical one

StudyOutput bouncing_ball_curve(const StudyContext&) {
  // the seeds' OpenGL example animates y(p) = A |cos(w p)| e^(-k p): its bounces (zeros of cos) are equally
  // spaced, pi / w apart, and its apexes fall by e^(-k pi / w) per bounce. Matched to the physical ball of
  // height A and restitution eps on the first rebound (flight 2 eps v0 / g) and on the apex ratio (eps^2),
  // the curve keeps every flight as long as the first, where the ball's shrink by eps each bounce.
  const Params ball{{"height", 1.0}, {"restitution", 0.8}, {"g", 9.81}, {"rest_speed", 0.01}};
  const auto impacts = bouncing_ball_impacts(ball, 1000);
  const double eps = ball.at("restitution"), g = ball.at("g");
  const double v0 = std::sqrt(2 * g * ball.at("height"));
  const double spacing = 2 * eps * v0 / g;           // the curve's pi / w
  const double k = -2 * std::log(eps) / spacing;     // e^(-k pi / w) = eps^2
  Table table{{"bounce", "physical_flight_s", "curve_flight_s", "curve_over_physical_flight", "physical_apex_m", "curve_apex_m"}, {}};
  std::string md = fmt::format("The seeds' OpenGL bouncing ball is an animation curve, y = A |cos(w p)| e^(-k p), not physics. "
                               "Matched to the physical ball (h0 = 1 m, eps = {}) on the first rebound's flight ({:.3f} s) and "
                               "on the apex ratio eps^2 per bounce (k = {:.3f} 1/s), its apexes agree bounce for bounce, "
                               "but its flights never shorten: the ball's shrink by eps each bounce and stop after {} impacts "
                               "at {:.3f} s, while the curve bounces on forever at a constant rhythm.\n\n"
                               "| bounce | physical flight (s) | curve flight (s) | curve / physical |\n|---|---|---|---|\n",
                               eps, spacing, k, impacts.size(), impacts.back().t);
  for (size_t n = 0; n + 1 < impacts.size(); ++n) {
    const double flight = impacts[n + 1].t - impacts[n].t;
    const double apex = impacts[n].apex;
    const double curve_apex = ball.at("height") * std::exp(-k * spacing * static_cast<double>(n + 1));
    table.rows.push_back({static_cast<long>(n + 1), flight, spacing, spacing / flight, apex, curve_apex});
    if (n < 5 || n + 2 == impacts.size()) md += fmt::format("| {} | {:.4f} | {:.4f} | {:.2f} |\n", n + 1, flight, spacing, spacing / flight);
  }
  std::vector<Figure> figures;
  md += "\n";
  md += add_figure(figures, "bouncing_ball_curve", "", "The seeds' animation curve against the physical ball, bounce by bounce");
  return {{{"bouncing_ball_curve", std::move(table)}}, md, figures};
}

// ---- event times and heights of the bouncing ball against its closed form, per method and step or tolerance

StudyOutput event_times(const StudyContext& ctx) {
  const bool quick = ctx.quick;
  const Params ball{{"height", 1.0}, {"restitution", 0.8}, {"g", 9.81}, {"rest_speed", 0.01}};
  const auto model = make_model("bouncing-ball", ball);
  const auto exact = bouncing_ball_impacts(ball, 1000);
  const double eps = ball.at("restitution"), g = ball.at("g"), v0 = std::sqrt(2 * g * ball.at("height"));
  // sampled at the exact apexes (after each impact but the last), so the heights are compared where they peak
  std::vector<double> t_out;
  for (size_t n = 0; n + 1 < exact.size(); ++n) t_out.push_back(exact[n].t + std::pow(eps, static_cast<double>(n + 1)) * v0 / g);
  const double t_end = exact.back().t + 0.5;
  t_out.push_back(t_end);

  Table table{{"method", "location", "dt", "rtol", "impacts", "exact_impacts", "max_time_error_s", "max_height_error_m", "rhs_evals", "status"}, {}};
  std::string md = fmt::format("The bouncing ball (h0 = 1 m, eps = {}) has {} impacts, the last ending in rest at {:.4f} s. Each run's "
                               "impact times against the closed form (the n-th found against the n-th exact, over those both have), "
                               "and its heights at the exact apex times against eps^(2n) h0. Fixed steps locate an impact on the "
                               "segment between the step's ends (the seeds' method) or by re-stepping to the root; CVODE finds "
                               "roots itself.\n\n| method | location | dt or rtol | impacts | max time error (s) | max height error (m) |\n|---|---|---|---|---|---|\n",
                               eps, exact.size(), exact.back().t);
  auto record = [&](const std::string& method, const std::string& location, std::optional<double> dt, std::optional<double> rtol,
                    const StepControl& control) {
    const RunResult r = make_integrator(method, control)->integrate(*model, 0, model->initial_state(), t_out);
    double time_error = 0, height_error = 0;
    const size_t matched = std::min(r.events.size(), exact.size());
    for (size_t n = 0; n < matched; ++n) time_error = std::max(time_error, std::abs(r.events[n].t - exact[n].t));
    for (size_t n = 0; n + 1 < std::min(r.trajectory.y.size(), exact.size()); ++n)
      height_error = std::max(height_error, std::abs(r.trajectory.y[n][0] - exact[n].apex));
    table.rows.push_back({method, location, dt ? Cell(*dt) : Cell(std::string()), rtol ? Cell(*rtol) : Cell(std::string()),
                          static_cast<long>(r.events.size()), static_cast<long>(exact.size()), time_error, height_error,
                          r.stats.rhs_evals, std::string(to_string(r.status))});
    md += fmt::format("| {} | {} | {} | {} | {} | {} |\n", method, location, dt ? fmt::format("dt {:g}", *dt) : fmt::format("rtol {:g}", *rtol),
                      r.events.size(), sci(time_error), sci(height_error));
  };
  const std::vector<double> dts = quick ? std::vector<double>{1e-3} : std::vector<double>{1e-2, 1e-3, 1e-4};
  const std::vector<double> rtols = quick ? std::vector<double>{1e-8} : std::vector<double>{1e-4, 1e-6, 1e-8, 1e-10};
  for (const std::string method : {"euler", "symplectic-euler", "rk4", "gsl-rk8pd"})
    for (const double dt : dts)
      for (const auto location : {EventLocation::linear, EventLocation::restep}) {
        StepControl control = StepControl::fixed(dt);
        control.event_location = location;
        record(method, location == EventLocation::linear ? "segment" : "restep", dt, std::nullopt, control);
      }
  for (const std::string method : {"cvode-adams", "cvode-bdf", "gsl-rkf45", "gsl-rk8pd"})
    for (const double rtol : rtols) {
      StepControl control = StepControl::adaptive(rtol, rtol * 1e-3);
      control.event_location = EventLocation::restep;
      record(method, method.starts_with("cvode") ? "rootfinding" : "restep", std::nullopt, rtol, control);
    }
  std::vector<Figure> figures;
  md += "\n";
  md += add_figure(figures, "event_times", "", "Largest impact-time error of the bouncing ball against the step or tolerance, per method and root location");
  return {{{"event_times", std::move(table)}}, md, figures};
}


// ---- wave stability: the largest stable dt of the seeds' two height-field schemes, against mu

StudyOutput wave_stability_study(const StudyContext& ctx) {
  const bool quick = ctx.quick;
  const int points = 32;
  const long steps = quick ? 1000 : 3000;
  const std::vector<double> mus = quick ? std::vector<double>{0, 0.5, 2, 10} : std::vector<double>{0, 0.5, 1, 2, 5, 10, 20, 50};
  Table table{{"method", "c", "d", "mu", "measured_dt", "derived_dt", "seeds_dt", "measured_over_derived", "seeds_over_measured"}, {}};
  std::string md = fmt::format(
      "The largest stable dt found by bisection (to 0.1%: {} steps from a random field on {}^2 points stay within 1e6 of "
      "the start), beside the limit derived from each scheme's amplification of its highest mode (solvers/wave_step.hpp) "
      "and the seeds' condition dt < (mu + sqrt(mu^2 + 32 c^2/d^2)) / (8 c^2/d^2).\n\n"
      "| method | c (m/s) | d (m) | mu (1/s) | measured dt (s) | derived (s) | seeds' (s) | measured / derived | seeds' / measured |\n"
      "|---|---|---|---|---|---|---|---|---|\n",
      steps, points);
  double worst_derived = 0, seeds_at_rest = 0, seeds_damped = 0;
  struct Point {
    std::string method;
    double c, d, mu;
  };
  std::vector<Point> plan;
  std::vector<std::string> labels;
  for (const std::string method : {"wave-fd", "symplectic-euler"})
    for (const auto& [c, d] : {std::pair{1.0, 0.02}, {2.0, 0.05}})
      for (const double mu : mus) {
        plan.push_back({method, c, d, mu});
        labels.push_back(fmt::format("{} c {:g} d {:g} mu {:g}", method, c, d, mu));
      }
  const auto found = ctx.sweep<WaveStability>(labels, [&](size_t i) {
    const Point& p = plan[i];
    return wave_stability(p.method, points, p.d, p.c, p.mu, steps);
  });
  for (size_t i = 0; i < plan.size(); ++i) {
    const auto& [method, c, d, mu] = plan[i];
    const WaveStability& w = found[i];
    table.rows.push_back({method, c, d, mu, w.measured, w.derived, w.seeds, w.measured / w.derived, w.seeds / w.measured});
    md += fmt::format("| {} | {} | {} | {} | {:.5g} | {:.5g} | {:.5g} | {:.4f} | {:.4f} |\n", method, c, d, mu, w.measured, w.derived,
                      w.seeds, w.measured / w.derived, w.seeds / w.measured);
    worst_derived = std::max(worst_derived, std::abs(w.measured / w.derived - 1));
    if (mu == 0) seeds_at_rest = std::max(seeds_at_rest, 1 - w.seeds / w.derived);
    else seeds_damped = std::max(seeds_damped, w.seeds / w.measured - 1);
  }
  md += fmt::format(
      "\nThe derived limits hold to {:.2f}% everywhere. The seeds' condition is right without damping (its 8 c^2/d^2 "
      "bounds the grid's highest eigenvalue from above, so it errs safe, by {:.2f}%), and wrong with damping: it grows with "
      "mu while neither scheme's limit does (the three-level scheme's is independent of mu; symplectic Euler's, damping "
      "explicit, shrinks), and promises up to {:.1f}% more than the schemes give — a run at the seeds' dt diverges. It is the "
      "limit of the scheme with the damping taken implicitly.\n\n",
      100 * worst_derived, 100 * seeds_at_rest, 100 * seeds_damped);
  std::vector<Figure> figures;
  md += add_figure(figures, "wave_stability", "", "Largest stable step of the height field against damping: measured, derived, the seeds' condition");
  return {{{"wave_stability", std::move(table)}}, md, figures};
}

// ---- rigid body: what the structure-preserving splitting buys over rk4 and CVODE at equal cost

StudyOutput rigid_body_invariants(const StudyContext& ctx) {
  const bool quick = ctx.quick;
  // a generic tumble (I = 1, 2, 3; w0 = (0.3, 1, 0.2): period 21 s), long enough for drift to show
  const double t_end = quick ? 200 : 2000;
  const Eigen::Vector3d inertia(1, 2, 3), w0(0.3, 1.0, 0.2);
  const auto model = make_model("rigid-body", {{"I1", inertia[0]}, {"I2", inertia[1]}, {"I3", inertia[2]}, {"wx0", w0[0]}, {"wy0", w0[1]}, {"wz0", w0[2]}});
  const double period = TorqueFreeRotation(inertia, w0).period();
  const std::vector<double> t_out = output_times(t_end, t_end / 400);
  Table table{{"method", "dt", "rtol", "rhs_evals", "cpu_seconds", "energy_first_half", "energy_second_half", "momentum_first_half",
               "momentum_second_half", "quaternion_norm_error", "status"},
              {}};
  std::string md = fmt::format(
      "A torque-free body tumbling for {:.0f} s (I = 1, 2, 3 kg m^2, w0 = (0.3, 1, 0.2) rad/s, {:.0f} periods of {:.2f} s). Largest "
      "relative energy error and world angular momentum error over the first and the second half: an error the same in both "
      "is bounded, one that grows drifts. rk4 runs at four times the splitting's step (four evaluations a step to its one), "
      "so each pair of rows costs the same number of evaluations.\n\n"
      "| method | dt (s) | rtol | evaluations | CPU (s) | energy, 1st half | energy, 2nd half | L, 1st half | L, 2nd half | quaternion norm error |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n",
      t_end, t_end / period, period);
  Table series{{"method", "dt", "rtol", "t", "energy_error", "momentum_error"}, {}};
  auto record = [&](const std::string& method, std::optional<double> dt, std::optional<double> rtol) {
    const StepControl control = dt ? StepControl::fixed(*dt) : StepControl::adaptive(*rtol, *rtol * 1e-3);
    const RunResult r = make_integrator(method, control)->integrate(*model, 0, model->initial_state(), t_out);
    const InvariantDrift d = rigid_body_drift(*model, r);
    for (size_t k = 0; k < r.trajectory.t.size(); ++k) {
      const InvariantError e = rigid_body_error(*model, r.trajectory.y[k]);
      series.rows.push_back({method, dt.value_or(NAN), rtol.value_or(NAN), r.trajectory.t[k], e.energy, e.momentum});
    }
    const double q_error = std::abs(r.y_stop.segment<4>(6).norm() - 1);
    table.rows.push_back({method, dt.value_or(NAN), rtol.value_or(NAN), r.stats.rhs_evals, r.stats.cpu_seconds, d.energy[0], d.energy[1],
                          d.momentum[0], d.momentum[1], q_error, std::string(to_string(r.status))});
    md += fmt::format("| {} | {} | {} | {} | {:.2e} | {} | {} | {} | {} | {} |\n", method, dt ? fmt::format("{:g}", *dt) : "—",
                      rtol ? fmt::format("{:g}", *rtol) : "—", r.stats.rhs_evals, r.stats.cpu_seconds, sci(d.energy[0]), sci(d.energy[1]),
                      sci(d.momentum[0]), sci(d.momentum[1]), sci(q_error));
    return std::pair{d, r.stats};
  };
  std::string findings;
  for (const double h : {0.05, 0.0125}) {
    const auto [split, split_stats] = record("rigid-splitting", h, std::nullopt);
    const auto [rk4, rk4_stats] = record("rk4", 4 * h, std::nullopt);
    findings += fmt::format(
        "- At {:.0f} evaluations: the splitting's energy error grows by {:.2f}x from the first half to the second and its L error "
        "stays at {}, rk4's grow by {:.2f}x and {:.2f}x; rk4's energy error at the end is {:.2g} times the splitting's; the splitting "
        "takes {:.1f}x rk4's CPU time (five rotations a step against four cheap evaluations).\n",
        static_cast<double>(split_stats.rhs_evals), split.energy[1] / split.energy[0], sci(split.momentum[1]), rk4.energy[1] / rk4.energy[0], rk4.momentum[1] / rk4.momentum[0],
        rk4.energy[1] / split.energy[1], split_stats.cpu_seconds / rk4_stats.cpu_seconds);
  }
  for (const double rtol : {1e-6, 1e-9}) {
    record("cvode-adams", std::nullopt, rtol);
    record("cvode-bdf", std::nullopt, rtol);
  }
  md += "\n" + findings +
        "\nCVODE Adams cannot project (SUNDIALS projects for BDF only): its quaternion norm error (| |q| - 1 |) is the quaternion's drift.\n\n";
  std::vector<Figure> figures;
  md += add_figure(figures, "rigid_body_invariants", "", "Energy and angular momentum errors of the tumbling body over time, per method and step");
  return {{{"rigid_body_invariants", std::move(table)}, {"rigid_body_invariants_series", std::move(series)}}, md, figures};
}

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
      "per CPU second, impacts, and the fraction of the energy left.\n\n"
      "| dt (s) | tumble: impacts | at rest (s) | below hz (m) | slope creep (m) | slide error | collapse: steps/s | impacts | energy kept |\n"
      "|---|---|---|---|---|---|---|---|---|\n",
      rest_time, collapse_time);
  double worst_creep = 0, worst_slide = 0, fewest_kept = 1, most_kept = 0;
  std::pair<size_t, size_t> impacts{std::numeric_limits<size_t>::max(), 0};
  struct Row {
    size_t tumble_impacts = 0, collapse_impacts = 0;
    double rest = 0, sink = 0, creep = 0, slide_error = 0, rate = 0, kept = 0;
    bool ok = false;
  };
  const std::vector<double> dts{4e-3, 2e-3, 1e-3, 5e-4};
  std::vector<std::string> labels;
  for (const double dt : dts) labels.push_back(fmt::format("dt {:g}", dt));
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
  });
  for (size_t i = 0; i < dts.size(); ++i) {
    const Row& r = rows[i];
    table.rows.push_back({dts[i], static_cast<double>(r.tumble_impacts), r.rest, r.sink, r.creep, r.slide_error, r.rate,
                          static_cast<double>(r.collapse_impacts), r.kept, std::string(r.ok ? "ok" : "failed")});
    worst_creep = std::max(worst_creep, r.creep);
    worst_slide = std::max(worst_slide, r.slide_error);
    fewest_kept = std::min(fewest_kept, r.kept);
    most_kept = std::max(most_kept, r.kept);
    impacts = {std::min(impacts.first, r.collapse_impacts), std::max(impacts.second, r.collapse_impacts)};
    md += fmt::format("| {:g} | {} | {:.2f} | {} | {} | {} | {:.0f} | {} | {:.3f} |\n", dts[i], r.tumble_impacts, r.rest, sci(r.sink), sci(r.creep),
                      sci(r.slide_error), r.rate, r.collapse_impacts, r.kept);
  }
  md += fmt::format(
      "\n- Over every dt the resting box moved at most {} m along the slope and the sliding box's speed was within {} of "
      "Coulomb's: velocity-level contact holds both exactly at any step, to round-off.\n"
      "- The collapse is chaotic: from dt to dt its impacts range over {}-{} and the energy it keeps over {:.3f}-{:.3f}, though "
      "a run repeated is bit-identical. The bounce changes with the step too (a step resolves one approach at a time).\n\n",
      sci(worst_creep), sci(worst_slide), impacts.first, impacts.second, fewest_kept, most_kept);
  std::vector<Figure> figures;
  md += add_figure(figures, "contacts", "", "Contacts against the step: the resting box's sink and the slopes' errors, and the collapse's energy and impacts");
  return {{{"contacts", std::move(table)}}, md, figures};
}


// ---- cloth: where explicit methods fail against stiffness, implicit Euler's damping, what each spring family adds

StudyOutput cloth_study(const StudyContext& ctx) {
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
      "2 a / omega^2 (stable only through damping). Implicit Euler is run at 100 times symplectic Euler's limit.\n\n"
      "| c (N/m) | omega_max (rad/s) | a (1/s) | method | predicted dt (s) | measured dt (s) | measured / predicted |\n"
      "|---|---|---|---|---|---|---|\n",
      steps);
  double worst_symplectic = 0, rk4_low = 10, rk4_high = 0, euler_low = 1e9, euler_high = 0;
  bool implicit_all_ok = true;
  // the bisections, one point per (stiffness, method), and implicit Euler at 100 times symplectic Euler's limit
  const std::vector<std::string> explicit_methods{"symplectic-euler", "rk4", "euler"};
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
    md += fmt::format("| {} | {:.1f} | {:.3g} | {} | {:.4g} | {:.4g} | {:.3f} |\n", c, mode.omega, mode.damping, method, predicted, measured, ratio);
    if (method == "symplectic-euler") worst_symplectic = std::max(worst_symplectic, std::abs(ratio - 1));
    if (method == "rk4") rk4_low = std::min(rk4_low, ratio), rk4_high = std::max(rk4_high, ratio);
    if (method == "euler") euler_low = std::min(euler_low, ratio), euler_high = std::max(euler_high, ratio);
  }
  std::vector<Figure> figures;
  md += "\n";
  md += add_figure(figures, "cloth_stability", "", "Largest stable step against the sheet's stiffness: measured points, predicted lines");
  md += fmt::format(
      "\nSymplectic Euler's measured limit is its predicted one to {:.2f}% at every stiffness: it falls as 1/sqrt(c), three "
      "decades of stiffness costing a factor {:.0f} in step. rk4's measured limit lies {:.1f}-{:.1f}% above its prediction: near its "
      "damped boundary |R| grows so slowly that {} steps do not show it. Explicit Euler's prediction is safe, but the probe finds "
      "it {:.2f}-{:.2f} times too small: its growth per step near the limit, h (h omega^2 - 2a), is tiny, and its limit falls as "
      "1/c, not 1/sqrt(c). Implicit Euler {} at 100 times symplectic Euler's step at every stiffness, its energy below where it "
      "started.\n\n",
      100 * worst_symplectic, std::sqrt(stiffnesses.back() / stiffnesses.front()), 100 * (rk4_low - 1), 100 * (rk4_high - 1), steps,
      euler_low, euler_high, implicit_all_ok ? "stays bounded" : "did NOT stay bounded everywhere");

  // implicit Euler's numerical damping on one linear spring: amplitude per step against 1 / sqrt(1 + w^2 h^2)
  Table damping{{"omega_h", "measured_ratio", "predicted_ratio", "periods_to_halve"}, {}};
  md += "Implicit Euler's numerical damping: one mass on one undamped spring (w = 20 rad/s), the amplitude sqrt(w^2 u^2 + v^2) "
        "kept per step against 1 / sqrt(1 + w^2 h^2).\n\n| w h | measured | 1 / sqrt(1 + w^2 h^2) | periods to halve |\n|---|---|---|---|\n";
  std::map<double, double> halving;
  double worst_damping = 0;
  for (const double wh : {0.01, 0.1, 0.5, 1.0, 3.0}) {
    const double ratio = implicit_euler_amplitude_ratios(wh, 1)[0];
    const double predicted = 1 / std::sqrt(1 + wh * wh);
    const double halve = std::log(2) / -std::log(ratio) * wh / (2 * std::numbers::pi);
    damping.rows.push_back({wh, ratio, predicted, halve});
    halving[wh] = halve;
    worst_damping = std::max(worst_damping, std::abs(ratio / predicted - 1));
    md += fmt::format("| {} | {:.12f} | {:.12f} | {:.3g} |\n", wh, ratio, predicted, halve);
  }
  md += "\n";
  md += add_figure(figures, "cloth_implicit_damping", "", "Implicit Euler's amplitude kept per step against w h");
  md += fmt::format(
      "\nThe measured ratio is 1 / sqrt(1 + w^2 h^2) to {:.1e}. A mode at w h = 0.01 (628 steps a period) loses half its amplitude "
      "in {:.3g} periods, at w h = 0.1 (63 steps a period) in {:.3g}; a cloth's stiff in-plane modes (w h >> 1) are gone within a step or two: "
      "implicit Euler is stable there by removing them.\n\n",
      worst_damping, halving[0.01], halving[0.1]);

  // what each spring family adds: the sheet hanging from two corners, 16 x 16, 3 s
  Table families{{"structural", "shear", "bend", "y_min", "max_stretch", "cpu_seconds", "status"}, {}};
  md += "What each spring family adds: the 16 x 16 sheet hanging from two corners for 3 s (implicit-euler, dt = 0.01).\n\n"
        "| structural | shear | bend | lowest point (m) | largest stretch | CPU (s) |\n|---|---|---|---|---|---|\n";
  std::vector<Eigen::VectorXd> ends;
  for (const auto& [shear, bend] : {std::pair{0, 0}, {1, 0}, {1, 1}}) {
    const auto model = make_model("cloth", {{"rows", 16}, {"columns", 16}, {"pin_corners", 0}, {"pin_top_corners", 1}, {"wind_coefficient", 0},
                                            {"shear", shear}, {"bend", bend}, {"damping", 0.05}, {"drag", 0.1}});
    const Measured m = run_and_measure(*model, "implicit-euler", StepControl::fixed(0.01), 3.0, 3.0);
    const Eigen::VectorXd end = model->summary(m.result.y_stop);
    families.rows.push_back({1.0, static_cast<double>(shear), static_cast<double>(bend), end[5], end[6], m.result.stats.cpu_seconds,
                             std::string(to_string(m.result.status))});
    md += fmt::format("| 1 | {} | {} | {:.4f} | {:.4f} | {:.3f} |\n", shear, bend, end[5], end[6], m.result.stats.cpu_seconds);
    ends.push_back(end);
  }
  md += fmt::format(
      "\nStructural springs alone leave the sheet free to shear: adding the shear springs moves its lowest point by {:.3f} m and "
      "its largest stretch from {:.3f} to {:.3f}. The bend springs then move the lowest point by only {:.4f} m: a sheet hanging "
      "in its own plane barely bends, so for this scene they are model it does not need.\n\n",
      ends[1][5] - ends[0][5], ends[0][6], ends[1][6], ends[2][5] - ends[1][5]);

  // momentum: a free sheet (no pins, gravity, drag or wind) pulled by one corner; its momentum is exactly F t
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
      "methods run at half symplectic Euler's limit ({:.3g} s), the implicit ones at 10 times that.\n\n"
      "| method | dt (s) | momentum error | CPU (s) |\n|---|---|---|---|\n",
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
    md += fmt::format("| {} | {:.3g} | {} | {:.3f} |\n", momentum_runs[i].first, momentum_runs[i].second, sci(error), r.stats.cpu_seconds);
  }
  const auto momentum_error = [&](size_t i) { return std::get<double>(momentum.rows[i][2]); };
  md += fmt::format(
      "\nThe springs' forces cancel in pairs in every evaluation, so the explicit methods keep F t to round-off ({} and {}). Implicit "
      "Euler's K and D have zero block-row sums (the springs do not care where the sheet is), so each of its solves adds h F to the "
      "momentum: {} with CG from a kept factor, {} with Newton. Liu's method keeps it to {}: the truncation of its 10 iterations.\n\n",
      sci(momentum_error(0)), sci(momentum_error(1)), sci(momentum_error(2)), sci(momentum_error(3)), sci(momentum_error(4)));
  return {{{"cloth_stability", std::move(limits)}, {"cloth_implicit_damping", std::move(damping)}, {"cloth_families", std::move(families)},
           {"cloth_momentum", std::move(momentum)}},
          md, figures};
}

}  // namespace

std::string sci(double v) { return std::isfinite(v) ? fmt::format("{:.2e}", v) : "—"; }

std::string add_figure(std::vector<Figure>& figures, const std::string& kind, const std::string& subject, const std::string& caption) {
  figures.push_back({kind, subject});
  return fmt::format("![{}]({}.png)\n\n", caption, figures.back().stem());
}

const std::vector<Study>& studies() {
  static const std::vector<Study> all = [] {
    std::vector<Study> list = accuracy_studies();
    list.insert(list.end(), {
      {"energy", "Energy over long runs", energy},
      {"adequacy", "Model adequacy: small-angle pendulum", adequacy},
      {"wave-adequacy", "Model adequacy: the wave equation against shallow water", wave_adequacy},
      {"bouncing-ball-curve", "Model adequacy: the seeds' animated bouncing ball", bouncing_ball_curve},
      {"event-times", "Events: the bouncing ball's impacts and apexes per method", event_times},
      {"wave-stability", "Stability: the height field's largest stable step against damping", wave_stability_study},
      {"rigid-body-invariants", "Energy and invariants: the torque-free rigid body per method at equal cost", rigid_body_invariants},
      {"contacts", "Contacts: a tumbling box, resting and sliding on slopes, and the collapsing wall, by step", contacts},
      {"cloth", "Cloth: explicit methods' limits against stiffness, implicit Euler's damping, the spring families", cloth_study},
    });
    return list;
  }();
  return all;
}

}  // namespace stepwise
