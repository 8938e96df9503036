#include "advise.hpp"

#include "report/cost_model.hpp"
#include "report/report.hpp"
#include "report/studies.hpp"
#include "report/studies/study_scenes.hpp"
#include "report/user_scene.hpp"
#include "run/atomic_write.hpp"
#include "run/csv.hpp"
#include "run/message.hpp"
#include "verification/reference.hpp"
#include "verification/stability.hpp"
#include "verification/tolerances.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>

namespace stepwise {

std::string_view to_string(Verdict verdict) {
  switch (verdict) {
    case Verdict::advised: return "advised";
    case Verdict::runner_up: return "runner-up";
    case Verdict::meets: return "meets";
    case Verdict::too_costly: return "too costly";
    case Verdict::unstable: return "unstable";
    case Verdict::failed: return "failed";
  }
  return "unknown";
}

std::string AdvisePoint::setting() const { return dt ? fmt::format("dt {:.4g}", *dt) : fmt::format("rtol {:.3g}", rtol); }

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// a short point's runs (least_of_runs)
constexpr int advise_runs = 3;
// the share of the budget the sweep may take; the rest is the reference, the spectrum, the reproduction and the
// outputs (measured: under 5% on the shipped scenes)
constexpr double sweep_share = 0.8;
// the most of the budget the reference may take (its runs are cut at that deadline, and the advice refused); the
// sweep then has what is left of its share
constexpr double reference_share = 0.5;
// the largest --budget taken: a day
constexpr double max_budget_seconds = 86400;
// the finest settings swept: rtol 1e-13, or t_end / 2^26 steps
constexpr int finest_rtol_exponent = 13, finest_halving = 26;

std::string fmt_seconds(double s) { return fmt::format("{:.3g} s", s); }

// what a run's error is measured against: the reference state at t_end (none: the exact solution), and where the
// scene has events of its own, the reference's event times
struct AdviseReference {
  std::optional<Eigen::VectorXd> y;
  std::optional<std::vector<double>> event_times;
};

// the larger of the state's error at t_end and the event times' (each found against the reference's n-th; a run
// that found a different number of events has not met any error)
double with_event_error(double state_error, const RunResult& r, const std::vector<double>& reference) {
  if (r.events.size() != reference.size()) return std::numeric_limits<double>::infinity();
  double error = state_error;
  for (size_t n = 0; n < reference.size(); ++n) error = std::max(error, std::abs(r.events[n].t - reference[n]));
  return error;
}

// a scene's own events (a ball that bounces at the wrong time is wrong, so their times count in the error): their
// times in the reference run; none for a scene without
std::optional<std::vector<double>> reference_event_times(const Model& model, double t_end, const ReferenceLimit& limit) {
  const auto events = events_of(model);
  if (std::none_of(events.begin(), events.end(), [](const Event& e) { return !e.surface; })) return std::nullopt;
  const RunResult r = reference_run(model, std::string(reference_method), StepControl::adaptive(reference_rtol, 1e-3 * reference_rtol), t_end, &limit,
                                    0, 0, "the reference run for the event times")
                          .result;
  if (r.status != Status::ok) throw std::runtime_error(fmt::format("advise: the reference run for the event times ({}) failed: {}", reference_method, r.message));
  std::vector<double> times;
  for (const auto& e : r.events) times.push_back(e.t);
  return times;
}

// the scene's error at t_end: against the exact solution where the model has one, else the reference state
AdvisePoint measure(const Model& model, const Method& method, const StepControl& control, double t_end, const AdviseReference& reference) {
  AdvisePoint p;
  p.method = std::string(method.name);
  p.dt = control.dt;
  if (!control.dt) {
    p.rtol = control.rtol;
    p.atol = control.atol;
  }
  const Measured best = least_of_runs(model, method.name, control, t_end, advise_runs);
  p.status = best.result.status;
  p.message = best.result.message;
  p.cpu_seconds = best.result.stats.cpu_seconds;
  p.rhs_evals = static_cast<double>(best.result.stats.rhs_evals);
  p.steps = best.result.stats.steps;
  if (p.status == Status::ok) p.error = reference.y ? max_norm_error(best.result.y_stop, *reference.y) : best.error;
  if (p.error && reference.event_times) p.error = with_event_error(*p.error, best.result, *reference.event_times);
  return p;
}

// one method's sweep: coarse to fine until it first meets the target, then the two settings between its last two
// (a third of the way each, geometrically), under its allowance of CPU seconds and the sweep's deadline
std::vector<AdvisePoint> sweep_method(const StudyScene& scene, const Method& method, double target, const AdviseReference& reference,
                                      Clock::time_point deadline, double allowance, int stride = 3) {
  const auto model = scene_model(scene);
  std::vector<AdvisePoint> points;
  double spent = 0;
  const bool adaptive = method.adaptive();
  // setting k of the sweep: rtol 10^-(2 + k/3) / dt t_end 2^-(3 + k/3), k in thirds of a decade or of a halving
  const auto control_at = [&](int thirds) {
    StepControl c;
    if (adaptive) {
      // three significant digits, so that the setting printed for `stepwise run` is the very tolerance swept
      const double rtol = std::stod(fmt::format("{:.3g}", std::pow(10.0, -2.0 - thirds / 3.0)));
      c = StepControl::adaptive(rtol, std::stod(fmt::format("{:.3g}", 1e-3 * rtol)));
    } else {
      const double steps = std::round(std::pow(2.0, 3.0 + thirds / 3.0));
      c = StepControl::fixed(scene.t_end / steps);
    }
    return c;
  };
  const int last = 3 * (adaptive ? finest_rtol_exponent - 2 : finest_halving - 3);
  const auto met = [&](const AdvisePoint& p) { return p.error && *p.error <= target; };
  for (int k = 0; k <= last; k += stride) {
    if (Clock::now() > deadline) break;
    StepControl control = control_at(k);
    // the next point's cost from the last one's: twice the steps a halving, an order-p pair's steps 10^(1/(p+1))
    // a decade (report/cost_model.hpp's rule), or its own last ratio when it has two points
    if (!points.empty()) {
      const AdvisePoint& prev = points.back();
      double growth = adaptive ? std::pow(10.0, 1.0 / (method.order.max + 1)) : 2.0;
      if (points.size() >= 2 && points[points.size() - 2].cpu_seconds > 0) growth = std::max(growth, prev.cpu_seconds / points[points.size() - 2].cpu_seconds);
      if (spent + prev.cpu_seconds * growth > allowance) break;
      // and its steps capped where its allowance would run out (a stiff system holding an explicit method)
      const double per_step = prev.steps > 0 ? prev.cpu_seconds / static_cast<double>(prev.steps) : 0;
      if (per_step > 0) control.max_steps = std::max<long>(1000, static_cast<long>((allowance - spent) / per_step));
    } else {
      control.max_steps = 2'000'000;
    }
    points.push_back(measure(*model, method, control, scene.t_end, reference));
    spent += points.back().cpu_seconds * (points.back().cpu_seconds > short_run_seconds ? 1 : advise_runs);
    if (!met(points.back())) continue;
    // between the last setting that missed and this one: the cheapest that meets it may lie there
    if (k > 0 && stride == 3 && !met(points[points.size() - 2]))
      for (int between : {k - 2, k - 1}) {
        if (Clock::now() > deadline) break;
        points.push_back(measure(*model, method, control_at(between), scene.t_end, reference));
        spent += points.back().cpu_seconds;
        if (met(points.back())) break;
      }
    break;
  }
  return points;
}

// the spectrum of the exact Jacobian at 16 points along a run of the scene
void spectrum_along_run(const StudyScene& scene, Advice& advice, Clock::time_point deadline) {
  const auto model = scene_model(scene);
  std::vector<double> times;
  for (int k = 0; k <= 16; ++k) times.push_back(scene.t_end * k / 16.0);
  // a stiff run is found out by the explicit one failing its step budget
  for (const std::string& m : {std::string("verner98"), std::string("cvode-bdf")}) {
    StepControl c = StepControl::adaptive(1e-8, 1e-11);
    c.max_steps = 200'000;
    const RunResult r = make_integrator(m, c)->integrate(*model, 0, model->initial_state(), std::span(times).subspan(1));
    if (r.status != Status::ok) continue;
    std::vector<Eigen::VectorXd> states{model->initial_state()};
    states.insert(states.end(), r.trajectory.y.begin(), r.trajectory.y.end());
    // (at the reference's deadline, the states' spectra so far)
    for (size_t k = 0; k < states.size() && Clock::now() < deadline; ++k) {
      const Eigen::VectorXcd lambda = leading_spectrum(*model, times[k], states[k]);
      for (const auto& l : lambda) {
        advice.fastest_decay = std::max(advice.fastest_decay, -l.real());
        advice.spectral_radius = std::max(advice.spectral_radius, std::abs(l));
      }
    }
    break;
  }
  advice.stiffness = scene.t_end * advice.fastest_decay;
  advice.stiff = advice.stiffness >= stiffness_threshold;
}

}  // namespace

std::vector<AdvisePoint> full_sweep(const StudyScene& scene, const Method& method, double target, const Eigen::VectorXd* reference_state, double seconds) {
  AdviseReference reference;
  if (reference_state) reference.y = *reference_state;
  return sweep_method(scene, method, target, reference, Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds)),
                      seconds, 1);
}

namespace {

// a method's verdict from its sweep's points: its cheapest point meeting the target, or why it has none (it diverged
// at the cheap steps, its runs failed, or it would cost more than its share of the budget); `searched` its stable
// step found by bisection, beside the spectrum's prediction
Candidate verdict(const Method& method, const std::vector<AdvisePoint>& pts, double target, const Eigen::VectorXcd& spectrum, std::optional<double> searched,
                  double fastest_decay) {
  Candidate c{std::string(method.name), Verdict::failed, "", std::nullopt, predicted_stable_dt(method, spectrum), searched};
  for (const auto& p : pts)
    if (p.error && *p.error <= target && (!c.cheapest || p.cpu_seconds < c.cheapest->cpu_seconds)) c.cheapest = p;
  if (c.cheapest) {
    c.status = Verdict::meets;
  } else if (pts.empty()) {
    c.status = Verdict::too_costly;
    c.reason = "not swept: the budget ran out first (the methods expected cheapest are swept first)";
  } else {
    const auto diverged = std::count_if(pts.begin(), pts.end(), [](const AdvisePoint& p) { return p.status == Status::diverged; });
    const auto failed = std::find_if(pts.begin(), pts.end(), [](const AdvisePoint& p) { return p.status == Status::failed; });
    const AdvisePoint* best = nullptr;
    for (const auto& p : pts)
      if (p.error && (!best || *p.error < *best->error)) best = &p;
    const std::string stable = c.predicted_stable_dt && std::isfinite(*c.predicted_stable_dt)
                                   ? fmt::format("; the spectrum (fastest decay {:.3g}/s) and its stability function predict stability for dt < {:.3g} s",
                                                 fastest_decay, *c.predicted_stable_dt)
                                   : "";
    if (diverged > 0 && (!best || diverged * 2 >= static_cast<long>(pts.size()) || pts.front().status == Status::diverged)) {
      c.status = Verdict::unstable;
      c.reason = fmt::format("diverged at the cheap steps ({} of its {} settings{}){}", diverged, pts.size(),
                             best ? fmt::format("; its best error {:.2e} cost {}", *best->error, fmt_seconds(best->cpu_seconds)) : "", stable);
    } else if (failed != pts.end() && !best) {
      c.status = Verdict::failed;
      c.reason = fmt::format("{} ({})", failed->message, failed->setting());
    } else {
      c.status = Verdict::too_costly;
      c.reason = best ? fmt::format("its best error {:.2e} (at {}) cost {} and the next setting would pass its share of the budget{}", *best->error,
                                    best->setting(), fmt_seconds(best->cpu_seconds), stable)
                      : fmt::format("no setting finished within its share of the budget{}", stable);
    }
  }
  return c;
}

}  // namespace

Advice advise(const StudyScene& scene, double target, double budget_seconds, int threads, const std::function<void(const std::string& line)>& progress) {
  const auto start = Clock::now();
  Advice advice;
  advice.scene = scene.label;
  advice.target = target;
  advice.budget_seconds = budget_seconds;
  const auto model = scene_model(scene);

  // what the errors are measured against, within the reference's share of the budget (ReferenceOutOfTime past it)
  const ReferenceLimit limit{start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(reference_share * budget_seconds)),
                             progress};
  AdviseReference reference;
  if (model->has_exact()) {
    advice.reference = "the exact solution";
  } else {
    const Reference r = converged_reference(*model, scene.t_end, &limit);
    reference.y = r.y;
    advice.reference = r.methods;
    advice.reference_agreement = r.agreement;
  }
  reference.event_times = reference_event_times(*model, scene.t_end, limit);
  if (reference.event_times) advice.event_count = reference.event_times->size();
  spectrum_along_run(scene, advice, limit.deadline);
  // the worst-case spectrum for the stability predictions: the eigenvalues at the start and the fastest decay seen
  Eigen::VectorXcd spectrum = leading_spectrum(*model, 0, model->initial_state());
  spectrum.conservativeResize(spectrum.size() + 1);
  spectrum[spectrum.size() - 1] = std::complex<double>(-advice.fastest_decay, 0);

  // the candidates: every method that applies (the GPU's need a device and a grid; dense matrices within the studies' budget)
  std::vector<const Method*> candidates;
  for (const auto& method : methods())
    if (method.family != Family::gpu && in_sweep(method, *model, true)) candidates.push_back(&method);
  const double elapsed_before = std::chrono::duration<double>(Clock::now() - start).count();
  const double sweep_seconds = std::max(0.0, budget_seconds * sweep_share - elapsed_before);
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(sweep_seconds));
  // each method's CPU allowance: its share of the sweep's seconds on all threads, four times over (most methods
  // finish in a small part of theirs; the deadline bounds the whole)
  const double allowance = 4 * sweep_seconds * threads / static_cast<double>(std::max<size_t>(1, candidates.size()));

  StudyContext ctx{false, threads, nullptr};
  ctx.distribute = false;
  std::vector<std::string> labels;
  std::vector<double> costs;
  // the sweep runs the costliest point first: given the inverse of each method's expected cost, the methods expected
  // cheapest (where the advice usually lies) run first and the deadline falls on the costly ones. The cost model
  // knows no stiffness: on a stiff system the methods that solve Newton systems go first (an explicit method's
  // sweep there runs into its stability limit and would spend the budget before they started)
  for (const Method* m : candidates) {
    labels.push_back(std::string(m->name));
    const double expected = expected_run_ns(*m, m->adaptive() ? StepControl::adaptive(1e-8, 1e-11) : StepControl::fixed(scene.time_scale), scene.t_end,
                                            scene.time_scale, model->size());
    costs.push_back((advice.stiff && solves_newton_systems(*m) ? 1e6 : 1.0) / expected);
  }
  const auto sweeps = ctx.sweep<std::vector<AdvisePoint>>(labels, [&](size_t i) {
    return sweep_method(scene, *candidates[i], target, reference, deadline, allowance);
  }, costs);

  const auto search_deadline = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(0.9 * budget_seconds));
  // the explicit fixed-step methods' stable steps found by search beside the spectrum's prediction (as the report's
  // stability section does): bisection between a quarter and 16 times the prediction, 2000 steps from the initial
  // state staying within 1e6 of it, while the budget lasts
  const auto searched = ctx.sweep<std::optional<double>>(labels, [&](size_t i) -> std::optional<double> {
    const Method& method = *candidates[i];
    if (!method.fixed_step() || solves_newton_systems(method) || Clock::now() > search_deadline) return std::nullopt;
    const auto predicted = predicted_stable_dt(method, spectrum);
    if (!predicted || !std::isfinite(*predicted) || !(*predicted > 0)) return std::nullopt;
    const auto probe = scene_model(scene);
    return bisect_stability([&](double dt) { return stays_bounded(*probe, method.name, probe->initial_state(), dt, 2000); }, *predicted / 4,
                            *predicted * 16, tolerance::stability_bisection_width);
  });

  // each method's verdict
  for (size_t i = 0; i < candidates.size(); ++i) {
    const Method& method = *candidates[i];
    const auto& pts = sweeps[i];
    advice.points.insert(advice.points.end(), pts.begin(), pts.end());
    Candidate c = verdict(method, pts, target, spectrum, searched[i], advice.fastest_decay);
    advice.candidates.push_back(std::move(c));
  }
  std::stable_sort(advice.candidates.begin(), advice.candidates.end(), [](const Candidate& a, const Candidate& b) {
    if (a.cheapest.has_value() != b.cheapest.has_value()) return a.cheapest.has_value();
    return a.cheapest && a.cheapest->cpu_seconds < b.cheapest->cpu_seconds;
  });
  if (!advice.candidates.empty() && advice.candidates[0].cheapest) {
    Candidate& best = advice.candidates[0];
    best.status = Verdict::advised;
    for (size_t k = 1; k < advice.candidates.size(); ++k) {
      Candidate& c = advice.candidates[k];
      if (!c.cheapest) break;
      c.status = k == 1 ? Verdict::runner_up : Verdict::meets;
      c.reason = fmt::format("{:.2f} times the advised method's CPU time ({} against {})", c.cheapest->cpu_seconds / best.cheapest->cpu_seconds,
                             fmt_seconds(c.cheapest->cpu_seconds), fmt_seconds(best.cheapest->cpu_seconds));
    }
    // the advised setting run again as `stepwise run` runs it: the same model, method and step control
    StepControl control = best.cheapest->dt ? StepControl::fixed(*best.cheapest->dt) : StepControl::adaptive(best.cheapest->rtol, best.cheapest->atol);
    advice.reproduced = measure(*scene_model(scene), *find_method(best.method), control, scene.t_end, reference);
  }
  advice.elapsed_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return advice;
}

namespace {

nlohmann::json point_json(const AdvisePoint& p) {
  nlohmann::json j{{"method", p.method}, {"cpu_seconds", p.cpu_seconds}, {"steps", p.steps}, {"rhs_evals", p.rhs_evals},
                   {"status", std::string(to_string(p.status))}};
  if (p.dt) j["dt"] = *p.dt;
  else {
    j["rtol"] = p.rtol;
    j["atol"] = p.atol;
  }
  j["error"] = p.error ? nlohmann::json(*p.error) : nlohmann::json(nullptr);
  return j;
}

}  // namespace

std::string advice_markdown(const Advice& a, const std::string& command, const std::string& heading) {
  std::string md = fmt::format("{} Advice for {}: error {:.1e} at t_end\n\n", heading, a.scene, a.target);
  const Candidate* best = !a.candidates.empty() && a.candidates[0].cheapest ? &a.candidates[0] : nullptr;
  if (best) {
    const AdvisePoint& p = *best->cheapest;
    md += fmt::format("**Use `{}` at {}{}**: error {:.2e} in {} of CPU.", best->method, p.setting(),
                      p.dt ? "" : fmt::format(", atol {:.3g}", p.atol), *p.error, fmt_seconds(p.cpu_seconds));
    if (a.candidates.size() > 1 && a.candidates[1].cheapest)
      md += fmt::format(" Runner-up: `{}` at {}, {:.2f} times its cost.", a.candidates[1].method, a.candidates[1].cheapest->setting(),
                        a.candidates[1].cheapest->cpu_seconds / p.cpu_seconds);
    md += fmt::format("\n\n    stepwise run SCENE --method {} {} --out DIR\n\n", best->method,
                      p.dt ? fmt::format("--dt {:.17g}", *p.dt) : fmt::format("--rtol {:g} --atol {:g}", p.rtol, p.atol));
    if (a.reproduced)
      md += fmt::format("Run again so, it gave error {} ({}).\n\n", a.reproduced->error ? fmt::format("{:.2e}", *a.reproduced->error) : "none",
                        to_string(a.reproduced->status));
  } else {
    md += "**No method met this error within the budget**: a larger --budget, or a larger error.\n\n";
  }
  md += fmt::format("The system is {}: the exact Jacobian's fastest decay along the run is {:.3g}/s (spectral radius {:.3g}/s); times the run's "
                    "{:.3g} s, a stiffness of {:.3g}{}.\n\n",
                    a.stiff ? "**stiff**" : "not stiff", a.fastest_decay, a.spectral_radius, a.stiffness / std::max(a.fastest_decay, 1e-300), a.stiffness,
                    a.stiff ? fmt::format(" (at least {}): an explicit method is held to steps near 2.8 / {:.3g} s (rk4's region) whatever the error asked, "
                                          "while an implicit one's steps follow the accuracy",
                                          stiffness_threshold, a.fastest_decay)
                            : fmt::format(" (below {}): explicit methods are limited by accuracy, not stability", stiffness_threshold));
  if (a.event_count)
    md += fmt::format("The scene has events ({} in the reference run): a run's error is the larger of its state's at t_end and its "
                      "event times' (s), each against the reference's; a run that finds a different number of events meets no error.\n\n",
                      *a.event_count);
  md += fmt::format("Errors are max-norm at t_end against {}{}. The sweep ran every method that applies, coarse to fine until it met the error "
                    "(then between its last two settings), each within its share of a {} budget: {} in all.\n\n",
                    a.reference, a.reference_agreement > 0 ? fmt::format(" (their runs agree to {:.2e})", a.reference_agreement) : "",
                    fmt_seconds(a.budget_seconds), fmt_seconds(a.elapsed_seconds));
  md += "![Work-precision of the advice's sweep](advice_" + a.scene + ".png)\n\n";
  const Table candidates = advice_tables({a}).candidates;
  const auto dt_shown = [](const Cell& cell) {
    const double dt = std::get<double>(cell);
    return std::isinf(dt) ? std::string("any") : std::isnan(dt) ? std::string() : fmt::format("{:.3g}", dt);
  };
  const auto blank_nan = [](std::string spec) {
    return [spec](const Cell& cell) { return std::isnan(std::get<double>(cell)) ? std::string() : fmt::format(fmt::runtime(spec), std::get<double>(cell)); };
  };
  md += "Data: [advice_sweep.csv](advice_sweep.csv) (every point), [advice_candidates.csv](advice_candidates.csv) (this table), "
        "[advice_summary.csv](advice_summary.csv).\n\n";
  md += markdown_table(candidates, {{"method", "method"},
                                    {"verdict", "verdict"},
                                    {"setting", "setting"},
                                    {"error", "error", blank_nan("{:.2e}")},
                                    {"cpu_seconds", "CPU (s)", blank_nan("{:.2e}")},
                                    {"predicted_stable_dt", "stable dt from the spectrum (s)", dt_shown},
                                    {"searched_stable_dt", "found by search (s)", dt_shown},
                                    {"reason", "why"}});
  md += fmt::format("\nCommand: `{}`. The sweep's every point is in advice_sweep.csv.\n", command);
  return md;
}

AdviceTables advice_tables(const std::vector<Advice>& advices) {
  AdviceTables t{{{"scene", "method", "mode", "dt", "rtol", "error", "rhs_evals", "steps", "cpu_seconds", "status"}, {}},
                 {{"scene", "target_error", "method", "setting", "error", "cpu_seconds", "stiff", "stiffness", "elapsed_seconds"}, {}},
                 {{"scene", "method", "verdict", "setting", "error", "cpu_seconds", "predicted_stable_dt", "searched_stable_dt", "reason"}, {}}};
  for (const Advice& a : advices) {
    for (const auto& c : a.candidates)
      t.candidates.rows.push_back({a.scene, c.method, std::string(to_string(c.status)), c.cheapest ? c.cheapest->setting() : std::string(), c.cheapest ? *c.cheapest->error : NAN,
                                   c.cheapest ? c.cheapest->cpu_seconds : NAN, c.predicted_stable_dt.value_or(NAN), c.searched_stable_dt.value_or(NAN),
                                   c.reason});
    for (const auto& p : a.points)
      t.sweep.rows.push_back({a.scene, p.method, std::string(p.dt ? "fixed" : "adaptive"), p.dt.value_or(NAN), p.dt ? NAN : p.rtol, p.error.value_or(NAN),
                              p.rhs_evals, p.steps, p.cpu_seconds, std::string(to_string(p.status))});
    const AdvisePoint* best = !a.candidates.empty() && a.candidates[0].cheapest ? &*a.candidates[0].cheapest : nullptr;
    t.summary.rows.push_back({a.scene, a.target, best ? best->method : std::string("none"), best ? best->setting() : std::string(),
                              best ? *best->error : NAN, best ? best->cpu_seconds : NAN, static_cast<long>(a.stiff), a.stiffness, a.elapsed_seconds});
  }
  return t;
}

nlohmann::json advice_json(const Advice& a, const std::string& scene_file) {
  nlohmann::json j;
  j["scene"] = a.scene;
  j["scene_file"] = scene_file;
  j["target_error"] = a.target;
  j["budget_seconds"] = a.budget_seconds;
  j["elapsed_seconds"] = a.elapsed_seconds;
  j["reference"] = a.reference;
  j["reference_agreement"] = a.reference_agreement;
  j["stiff"] = a.stiff;
  j["stiffness"] = a.stiffness;
  j["fastest_decay"] = a.fastest_decay;
  j["spectral_radius"] = a.spectral_radius;
  const Candidate* best = !a.candidates.empty() && a.candidates[0].cheapest ? &a.candidates[0] : nullptr;
  j["method"] = best ? nlohmann::json(best->method) : nlohmann::json(nullptr);
  if (best) {
    const AdvisePoint& p = *best->cheapest;
    if (p.dt) j["dt"] = *p.dt;
    else {
      j["rtol"] = p.rtol;
      j["atol"] = p.atol;
    }
    j["error"] = *p.error;
    j["cpu_seconds"] = p.cpu_seconds;
  }
  j["runner_up"] = nullptr;
  if (a.candidates.size() > 1 && a.candidates[1].cheapest) {
    j["runner_up"] = point_json(*a.candidates[1].cheapest);
    j["runner_up"]["cpu_over_advised"] = a.candidates[1].cheapest->cpu_seconds / best->cheapest->cpu_seconds;
  }
  j["reproduced"] = a.reproduced ? point_json(*a.reproduced) : nlohmann::json(nullptr);
  j["candidates"] = nlohmann::json::array();
  for (const auto& c : a.candidates) {
    nlohmann::json e{{"method", c.method}, {"status", to_string(c.status)}, {"reason", c.reason}};
    if (c.cheapest) e["cheapest"] = point_json(*c.cheapest);
    e["predicted_stable_dt"] = c.predicted_stable_dt && std::isfinite(*c.predicted_stable_dt) ? nlohmann::json(*c.predicted_stable_dt) : nlohmann::json(nullptr);
    e["searched_stable_dt"] = c.searched_stable_dt ? nlohmann::json(*c.searched_stable_dt) : nlohmann::json(nullptr);
    j["candidates"].push_back(e);
  }
  return j;
}

std::string advice_json_text(const Advice& a, const std::string& scene_file) { return advice_json(a, scene_file).dump(2) + "\n"; }

void check_advice_request(double error, double budget_seconds) {
  if (!(std::isfinite(error) && error > 0)) throw InputError(fmt::format("--error: must be a positive finite number, got {}", error));
  if (!(std::isfinite(budget_seconds) && budget_seconds >= 1 && budget_seconds <= max_budget_seconds))
    throw InputError(fmt::format("--budget: must be between 1 and {:g} seconds, got {}", max_budget_seconds, budget_seconds));
}

Figure advice_figure(const Advice& advice, const std::string& tables) {
  FigureSpec::Layer sweep{.table = tables + "_sweep", .x = "cpu_seconds", .y = "error", .where = {{"scene", {advice.scene}}}};
  FigureSpec::Panel panel{.title = fmt::format("{}: the advice's sweep (dashed: adaptive; x: failed or diverged)", advice.scene),
                          .x_label = "CPU time (s)", .y_label = "max-norm error at t_end", .log_x = true, .log_y = true, .layers = by_mode(sweep),
                          .lines = {{'y', advice.target, "the error asked"}}};
  panel.layers.push_back({.table = tables + "_summary", .x = "cpu_seconds", .y = "error", .series = "method", .label = "advised: {}", .mark = FigureMark::star,
                          .where = {{"scene", {advice.scene}}}, .hover = {{"setting", "setting"}}});
  return {tables, advice.scene, {.title = "The advice's sweep, " + advice.scene, .panels = {std::move(panel)}}};
}

int advise_command(const AdviseOptions& o) {
  // the inputs, before anything runs: the error, the budget, the scene as `stepwise run` checks it, the output
  check_advice_request(o.error, o.budget);
  PreparedRun prepared;
  const StudyScene scene = user_study_scene(o.run, &prepared);
  const bool out_existed = fs::exists(o.out);
  ensure_writable_directory(o.out);
  const int threads = threads_or_default(o.threads);
  Advice a;
  try {
    a = advise(scene, o.error, o.budget, threads, [](const std::string& line) { fmt::print(stderr, "stepwise advise: {}\n", line); });
  } catch (const ReferenceOutOfTime& cut) {
    // nothing written: the errors could not be measured (the output directory made for them removed again)
    std::error_code ignored;
    if (!out_existed) fs::remove(o.out, ignored);
    const double would_do = std::ceil(cut.estimated_seconds / reference_share);
    print_error("advise", fmt::format("{}: the converged reference cannot be had within its share ({:.3g} s) of --budget {:g}; at its pace so far, {}",
                                      cut.what(), reference_share * o.budget, o.budget,
                                      would_do <= max_budget_seconds ? fmt::format("about --budget {:.0f} would do", would_do)
                                                                     : fmt::format("more than the largest --budget ({:g} s)", max_budget_seconds)));
    return 1;
  }

  std::string command = fmt::format("stepwise advise {} --error {:g} --budget {:g}", o.run.scene_file, o.error, o.budget);
  for (const auto& s : o.run.sets) command += " --set " + s;
  const AdviceTables tables = advice_tables({a});
  const Candidate* best = !a.candidates.empty() && a.candidates[0].cheapest ? &a.candidates[0] : nullptr;
  const fs::path out(o.out);
  write_file_atomic(out / "advice_sweep.csv", to_csv(tables.sweep));
  write_file_atomic(out / "advice_summary.csv", to_csv(tables.summary));
  write_file_atomic(out / "advice_candidates.csv", to_csv(tables.candidates));
  write_file_atomic(out / "advice.json", advice_json_text(a, o.run.scene_file));
  const std::string md = advice_markdown(a, command, "#");
  write_file_atomic(out / "advice.md", md);
  draw_figures({advice_figure(a)}, out, 1, false);
  fmt::print("{}", md.substr(0, md.find("The system is")));
  return best ? 0 : 1;
}

}  // namespace stepwise
