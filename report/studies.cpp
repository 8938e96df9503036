#include "studies.hpp"

#include "models/bouncing_ball.hpp"
#include "models/model.hpp"
#include "models/pendulum.hpp"
#include "models/rigid_body.hpp"
#include "solvers/wave_step.hpp"
#include "verification/adequacy.hpp"
#include "verification/contact_checks.hpp"
#include "verification/convergence.hpp"
#include "verification/invariants.hpp"
#include "verification/measure.hpp"
#include "verification/stability.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

namespace stepwise {
namespace {

// a scene of the studies: a model with parameters, integrated from t = 0 to t_end
struct StudyScene {
  std::string label;
  std::string model;
  Params params;
  double t_end;
  double time_scale;  // fastest time scale (s): 1/w for the pendulum, 1/rate for the flow
};

std::vector<StudyScene> ode_scenes() {
  return {{"pendulum", "pendulum", {{"theta0", 1.0}}, 10.0, 0.25},
          {"flow-particle", "flow-particle", {}, 1.0, 1.0},
          {"projectile", "projectile", {{"drag", 0.5}}, 2.0, 1.0},
          // one particle of the particle system without repulsion: three damped oscillators, w = 2 rad/s
          {"particle-system", "particle-system", {{"count", 1}, {"repulsion", 0}}, 2.0, 0.5},
          // the (1, 2) mode of a 17^2 height field against its exact semi-discrete solution: the seeds' scheme
          // beside the method of lines. The time scale is 16 times the scheme's stability limit (0.044 s), so
          // wave-fd starts at half its limit and rk4 and the Euler family start past theirs (shown diverged)
          // and halve into stability
          {"standing-wave", "standing-wave", {{"size", 17}, {"spacing", 1.0 / 16}, {"c", 1}, {"mu", 0.5}, {"mode_m", 1}, {"mode_n", 2}, {"amplitude", 1}}, 2.0,
           16 * wave_stable_dt({17, 1.0 / 16, 1, 0.5})}};
}

// methods whose dense n x n matrices exceed this (362 unknowns) are left out of a scene's sweeps: a dense
// LU of the standing wave's 578 unknowns (64 MFLOP) at every step of every point would take the report's
// whole budget, and cvode-bdf (KLU on the sparse Jacobian) is there to represent the implicit methods
constexpr double dense_matrix_budget = 1 << 20;

constexpr std::string_view dense_note =
    "Methods that would keep dense n x n matrices larger than 1 MiB (the standing wave's 578 unknowns: implicit-euler, GSL's implicit "
    "steppers) are left out of a scene; cvode-bdf, with KLU on the sparse Jacobian, stands for the implicit methods there.\n\n";

bool in_sweep(const MethodInfo& method, const Model& model) {
  return method_applies(method, model) && dense_matrix_bytes(method, model) <= dense_matrix_budget;
}

std::string sci(double v) { return std::isfinite(v) ? fmt::format("{:.2e}", v) : "—"; }

// ---- convergence: error against dt for every fixed-step method, with the fitted order

StudyOutput convergence(bool quick) {
  const int halvings = quick ? 4 : 6;
  Table points{{"scene", "method", "dt", "steps", "rhs_evals", "error", "status"}, {}};
  Table orders{{"scene", "method", "documented_order", "observed_order"}, {}};
  std::string md = "Observed order: least-squares slope of log(error at t_end) against log(dt) over the halvings, fitted to "
                   "the errors between 1e-12 (round-off) and 1e-1 (pre-asymptotic), against the order of the method table. "
                   "GSL's multistep and extrapolation steppers (bsimp, msadams, msbdf) choose their order from the error "
                   "control, so their slope is only reported (nan: every error at round-off).\n\n" + std::string(dense_note);
  for (const auto& scene : ode_scenes()) {
    const auto model = make_model(scene.model, scene.params);
    md += fmt::format("### {}\n\n| method | order (method table) | observed order | error at coarsest dt | error at finest dt |\n|---|---|---|---|---|\n", scene.label);
    for (const auto& method : methods()) {
      if (!method.fixed_step || !in_sweep(method, *model)) continue;
      const ConvergenceSweep sweep = convergence_sweep(*model, method, scene.t_end, halvings, coarse_dt(method, scene.time_scale));
      for (size_t k = 0; k < sweep.runs.size(); ++k) {
        const Measured& m = sweep.runs[k];
        points.rows.push_back({scene.label, std::string(method.name), sweep.dt[k], m.result.stats.steps,
                               m.result.stats.rhs_evals, m.error.value_or(std::numeric_limits<double>::quiet_NaN()),
                               std::string(to_string(m.result.status))});
      }
      // errors of the coarsest and finest runs that succeeded, whether or not they entered the fit
      std::vector<double> errors;
      for (const auto& m : sweep.runs)
        if (m.error) errors.push_back(*m.error);
      const double slope = sweep.observed_order;
      orders.rows.push_back({scene.label, std::string(method.name), std::string(method.order), slope});
      md += fmt::format("| {} | {} | {:.2f} | {} | {} |\n", method.name, method.order, slope,
                        sci(errors.empty() ? NAN : errors.front()), sci(errors.empty() ? NAN : errors.back()));
    }
    md += "\n";
  }
  return {{{"convergence", std::move(points)}, {"convergence_orders", std::move(orders)}}, md};
}

// ---- work-precision: error against cost for every method

// minimum thread CPU time over `repeats` runs after one discarded warm-up run
Measured timed_run(const Model& model, std::string_view method, const StepControl& control, double t_end, int repeats) {
  Measured best = run_and_measure(model, method, control, t_end, t_end);
  for (int r = 0; r < repeats; ++r) {
    Measured m = run_and_measure(model, method, control, t_end, t_end);
    if (m.result.stats.cpu_seconds < best.result.stats.cpu_seconds || r == 0) best = std::move(m);
  }
  return best;
}

StudyOutput work_precision(bool quick) {
  const int repeats = quick ? 1 : 3;
  const int halvings = quick ? 4 : 7;
  std::vector<double> rtols;
  for (int e = 2; e <= 12; e += quick ? 2 : 1) rtols.push_back(std::pow(10.0, -e));
  const std::vector<double> targets{1e-3, 1e-6, 1e-9};

  Table points{{"scene", "method", "mode", "dt", "rtol", "error", "rhs_evals", "steps", "cpu_seconds", "status"}, {}};
  std::string md = "Error at t_end (max norm against the exact solution) against cost. Fixed-step methods are swept over "
                   "dt halvings, adaptive ones over rtol (atol = 1e-3 rtol). CPU time is the minimum over repeated runs "
                   "after a discarded warm-up. Failed or diverged points stay in the CSV with their status.\n\n" + std::string(dense_note);
  for (const auto& scene : ode_scenes()) {
    const auto model = make_model(scene.model, scene.params);
    // cheapest (by RHS evaluations and by CPU time) method reaching each target
    std::map<double, std::pair<std::string, double>> by_rhs, by_cpu;
    auto consider = [&](const std::string& label, const Measured& m) {
      if (!m.error) return;
      for (const double target : targets) {
        if (*m.error > target) continue;
        const double rhs = static_cast<double>(m.result.stats.rhs_evals);
        if (!by_rhs.contains(target) || rhs < by_rhs[target].second) by_rhs[target] = {label, rhs};
        if (!by_cpu.contains(target) || m.result.stats.cpu_seconds < by_cpu[target].second) by_cpu[target] = {label, m.result.stats.cpu_seconds};
      }
    };
    for (const auto& method : methods()) {
      if (!in_sweep(method, *model)) continue;
      if (method.fixed_step) {
        for (int k = 0; k <= halvings; ++k) {
          StepControl control;
          control.dt = coarse_dt(method, scene.time_scale) / std::pow(2.0, k);
          const Measured m = timed_run(*model, method.name, control, scene.t_end, repeats);
          points.rows.push_back({scene.label, std::string(method.name), std::string("fixed"), *control.dt, NAN,
                                 m.error.value_or(NAN), m.result.stats.rhs_evals, m.result.stats.steps,
                                 m.result.stats.cpu_seconds, std::string(to_string(m.result.status))});
          consider(fmt::format("{} (dt {:.3g})", method.name, *control.dt), m);
        }
      }
      if (method.adaptive) {
        for (const double rtol : rtols) {
          StepControl control;
          control.rtol = rtol;
          control.atol = 1e-3 * rtol;
          // a low-order method at a tight tolerance needs millions of steps (gsl-rk1imp at 1e-12: 3e7 steps,
          // 30 s): such a point is reported as failed past this budget rather than allowed to stall the report
          control.max_steps = 200'000;
          const Measured m = timed_run(*model, method.name, control, scene.t_end, repeats);
          points.rows.push_back({scene.label, std::string(method.name), std::string("adaptive"), NAN, rtol,
                                 m.error.value_or(NAN), m.result.stats.rhs_evals, m.result.stats.steps,
                                 m.result.stats.cpu_seconds, std::string(to_string(m.result.status))});
          consider(fmt::format("{} (rtol {:.0e})", method.name, rtol), m);
        }
      }
    }
    md += fmt::format("### {}\n\n| error target | cheapest in RHS evaluations | RHS evals | cheapest in CPU time | CPU s |\n|---|---|---|---|---|\n", scene.label);
    for (const double target : targets) {
      if (!by_rhs.contains(target)) {
        md += fmt::format("| {:.0e} | none reached it | | | |\n", target);
        continue;
      }
      md += fmt::format("| {:.0e} | {} | {:.0f} | {} | {:.2e} |\n", target, by_rhs[target].first, by_rhs[target].second,
                        by_cpu[target].first, by_cpu[target].second);
    }
    md += "\n";
  }
  return {{{"work_precision", std::move(points)}}, md};
}

// ---- energy: the pendulum over many periods

StudyOutput energy(bool quick) {
  const int periods = quick ? 100 : 1000;
  const int samples = 20;  // per period: the error oscillates within a period, so one sample a period would alias it
  const double theta0 = 0.5;
  const auto model = make_model("pendulum", {{"theta0", theta0}});
  const double period = pendulum_period(theta0, 9.81, 1.0);
  const double e0 = *model->energy(model->initial_state());
  Table table{{"method", "t", "relative_energy_error"}, {}};
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
    md += fmt::format("| {} | {:.3e} | {:.3e} | {:+.3e} |\n", method, max_abs(0, tenth), max_abs(n - tenth, n),
                      errors.empty() ? NAN : errors.back());
  }
  return {{{"energy", std::move(table)}}, md + "\n"};
}

// ---- adequacy: where the small-angle model stops being enough

StudyOutput adequacy(bool) {
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
  return {{{"adequacy", std::move(table)}}, md + "\n"};
}

// ---- the seeds' animated bouncing ball against the physical one

StudyOutput bouncing_ball_curve(bool) {
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
  Table table{{"bounce", "physical_flight_s", "curve_flight_s", "physical_apex_m", "curve_apex_m"}, {}};
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
    table.rows.push_back({static_cast<long>(n + 1), flight, spacing, apex, curve_apex});
    if (n < 5 || n + 2 == impacts.size()) md += fmt::format("| {} | {:.4f} | {:.4f} | {:.2f} |\n", n + 1, flight, spacing, spacing / flight);
  }
  return {{{"bouncing_ball_curve", std::move(table)}}, md + "\n"};
}

// ---- event times and heights of the bouncing ball against its closed form, per method and step or tolerance

StudyOutput event_times(bool quick) {
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
  return {{{"event_times", std::move(table)}}, md + "\n"};
}


// ---- wave stability: the largest stable dt of the seeds' two height-field schemes, against mu

StudyOutput wave_stability_study(bool quick) {
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
  for (const std::string method : {"wave-fd", "symplectic-euler"})
    for (const auto& [c, d] : {std::pair{1.0, 0.02}, {2.0, 0.05}})
      for (const double mu : mus) {
        const WaveStability w = wave_stability(method, points, d, c, mu, steps);
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
  return {{{"wave_stability", std::move(table)}}, md};
}

// ---- rigid body: what the structure-preserving splitting buys over rk4 and CVODE at equal cost

StudyOutput rigid_body_invariants(bool quick) {
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
      "| method | dt (s) | rtol | evaluations | CPU (s) | energy, 1st half | energy, 2nd half | L, 1st half | L, 2nd half | |q| - 1 |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n",
      t_end, t_end / period, period);
  auto record = [&](const std::string& method, std::optional<double> dt, std::optional<double> rtol) {
    const StepControl control = dt ? StepControl::fixed(*dt) : StepControl::adaptive(*rtol, *rtol * 1e-3);
    const RunResult r = make_integrator(method, control)->integrate(*model, 0, model->initial_state(), t_out);
    const InvariantDrift d = rigid_body_drift(*model, r);
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
        "\nCVODE Adams cannot project (SUNDIALS projects for BDF only): its |q| - 1 column is the quaternion's drift.\n\n";
  return {{{"rigid_body_invariants", std::move(table)}}, md};
}

StudyOutput contacts(bool quick) {
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
  for (const double dt : {4e-3, 2e-3, 1e-3, 5e-4}) {
    const StepControl control = StepControl::fixed(dt);
    const auto box = make_model("dropped-body");  // its defaults are the scene's drop
    const Measured t = run_and_measure(*box, "sequential-impulses", control, 5.0, 0.01);
    const auto names = box->summary_names();
    const auto kinetic_at = std::find(names.begin(), names.end(), "kinetic") - names.begin();
    const double k0 = box->summary(box->initial_state())[kinetic_at];
    double rest = 0;
    for (size_t k = 0; k < t.result.trajectory.y.size(); ++k)
      if (box->summary(t.result.trajectory.y[k])[kinetic_at] > 1e-9 * k0) rest = t.result.trajectory.t[k];
    const double sink = hz - t.result.y_stop[2];
    const auto gentle_box = make_model("dropped-body", box_on_slope(gentle, mu));
    const SlopeMotion held = slope_motion(run_and_measure(*gentle_box, "sequential-impulses", control, rest_time, 0.01).result, gentle, 0.05);
    const auto steep_box = make_model("dropped-body", box_on_slope(steep, mu));
    const SlopeMotion slid = slope_motion(run_and_measure(*steep_box, "sequential-impulses", control, 1.0, 0.1).result, steep, 0.05);
    const double slide_error = std::abs(slid.speed / coulomb - 1);
    const auto wall = make_model("box-stack");
    const RunResult c = make_integrator("sequential-impulses", control)->integrate(*wall, 0, wall->initial_state(), std::vector<double>{collapse_time});
    const double kept = *wall->energy(c.y_stop) / *wall->energy(wall->initial_state());
    const double rate = static_cast<double>(c.stats.steps) / c.stats.cpu_seconds;
    const bool ok = t.result.status == Status::ok && c.status == Status::ok;
    table.rows.push_back({dt, static_cast<double>(t.result.events.size()), rest, sink, held.creep, slide_error, rate,
                          static_cast<double>(c.events.size()), kept, std::string(ok ? "ok" : "failed")});
    worst_creep = std::max(worst_creep, held.creep);
    worst_slide = std::max(worst_slide, slide_error);
    fewest_kept = std::min(fewest_kept, kept);
    most_kept = std::max(most_kept, kept);
    impacts = {std::min(impacts.first, c.events.size()), std::max(impacts.second, c.events.size())};
    md += fmt::format("| {:g} | {} | {:.2f} | {} | {} | {} | {:.0f} | {} | {:.3f} |\n", dt, t.result.events.size(), rest, sci(sink), sci(held.creep),
                      sci(slide_error), rate, c.events.size(), kept);
  }
  md += fmt::format(
      "\n- Over every dt the resting box moved at most {} m along the slope and the sliding box's speed was within {} of "
      "Coulomb's: velocity-level contact holds both exactly at any step, to round-off.\n"
      "- The collapse is chaotic: from dt to dt its impacts range over {}-{} and the energy it keeps over {:.3f}-{:.3f}, though "
      "a run repeated is bit-identical. The bounce changes with the step too (a step resolves one approach at a time).\n\n",
      sci(worst_creep), sci(worst_slide), impacts.first, impacts.second, fewest_kept, most_kept);
  return {{{"contacts", std::move(table)}}, md};
}


// ---- cloth: where explicit methods fail against stiffness, implicit Euler's damping, what each spring family adds

StudyOutput cloth_study(bool quick) {
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
  std::string implicit_note;
  bool implicit_all_ok = true;
  for (const double c : stiffnesses) {
    const auto model = stability_sheet(c);
    const StiffestMode mode = stiffest_mode(*model, 0, model->initial_state());
    for (const std::string method : {"symplectic-euler", "rk4", "euler"}) {
      const double predicted = *mass_spring_stable_dt(method, mode);
      const double measured = measured_stable_dt(*model, method, steps, predicted);
      const double ratio = measured / predicted;
      limits.rows.push_back({c, method, mode.omega, mode.damping, predicted, measured, ratio});
      md += fmt::format("| {} | {:.1f} | {:.3g} | {} | {:.4g} | {:.4g} | {:.3f} |\n", c, mode.omega, mode.damping, method, predicted, measured, ratio);
      if (method == "symplectic-euler") worst_symplectic = std::max(worst_symplectic, std::abs(ratio - 1));
      if (method == "rk4") rk4_low = std::min(rk4_low, ratio), rk4_high = std::max(rk4_high, ratio);
      if (method == "euler") euler_low = std::min(euler_low, ratio), euler_high = std::max(euler_high, ratio);
    }
    const double dt = 100 * *mass_spring_stable_dt("symplectic-euler", mode);
    const Measured m = run_and_measure(*model, "implicit-euler", StepControl::fixed(dt), 2.0, 2.0);
    const bool ok = m.result.status == Status::ok && *model->energy(m.result.y_stop) < *model->energy(model->initial_state());
    implicit_all_ok = implicit_all_ok && ok;
    limits.rows.push_back({c, std::string("implicit-euler"), mode.omega, mode.damping, NAN, dt, NAN});
  }
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
  return {{{"cloth_stability", std::move(limits)}, {"cloth_implicit_damping", std::move(damping)}, {"cloth_families", std::move(families)}}, md};
}

}  // namespace

const std::vector<Study>& studies() {
  static const std::vector<Study> all{
      {"convergence", "Convergence", convergence},
      {"work-precision", "Accuracy against cost", work_precision},
      {"energy", "Energy over long runs", energy},
      {"adequacy", "Model adequacy: small-angle pendulum", adequacy},
      {"bouncing-ball-curve", "Model adequacy: the seeds' animated bouncing ball", bouncing_ball_curve},
      {"event-times", "Events: the bouncing ball's impacts and apexes per method", event_times},
      {"wave-stability", "Stability: the height field's largest stable step against damping", wave_stability_study},
      {"rigid-body-invariants", "Energy and invariants: the torque-free rigid body per method at equal cost", rigid_body_invariants},
      {"contacts", "Contacts: a tumbling box, resting and sliding on slopes, and the collapsing wall, by step", contacts},
      {"cloth", "Cloth: explicit methods' limits against stiffness, implicit Euler's damping, the spring families", cloth_study},
  };
  return all;
}

}  // namespace stepwise
