// The report's study: constraints: the Cartesian pendulum and the chain stepped the ways engines and offline codes
// keep a constraint (an ODE method on the constrained equations, plain, projected or Baumgarte-stabilised;
// RATTLE; position-based dynamics), measured like every other method: error against CPU, drift over long runs,
// XPBD's artificial damping, Macklin et al. (2019)'s substeps against iterations at equal cost, PBD's
// stiffness moving with its iteration count while XPBD's does not, and a compliant rod at frame steps under the
// solvers of backward Euler's step (vbd, xpbd, the linearised step, fast mass-spring) beside symplectic Euler.
#include "report/studies.hpp"
#include "run/measure.hpp"
#include "run/projected_model.hpp"

#include "models/model.hpp"
#include "models/pendulum.hpp"
#include "solvers/capabilities/distance_constraints.hpp"
#include "solvers/mass_spring_implicit.hpp"
#include "solvers/method_table.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <tuple>

namespace stepwise {
namespace {

// the stiffness table's rod (m/N), and Hooke's stretch of a 1 kg mass hanging on it (m)
constexpr double rod_compliance = 1e-3, hooke_stretch = 9.81 * rod_compliance;

// how an ODE method is kept on the constraints ("" plain, "projection", "baumgarte"), or which of a position-based
// method's knobs a sweep turns ("small steps": substeps of one iteration; "iterations": one substep)
std::unique_ptr<Model> constrained(const std::string& name, Params params, const std::string& variant) {
  if (variant == "baumgarte") params["baumgarte"] = 1;
  auto model = make_model(name, params);
  return variant == "projection" ? projected(std::move(model)) : std::move(model);
}

StepControl position_based(double dt, int substeps, int iterations) {
  StepControl c = StepControl::fixed(dt);
  c.settings["substeps"] = substeps;
  c.settings["iterations"] = iterations;
  return c;
}

// a setting's substeps or iterations as the tables show them: as set, else xpbd's defaults (its registration's)
long knob(const StepControl& control, std::string_view name) {
  const auto at = control.settings.find(name);
  return static_cast<long>(at != control.settings.end() ? at->second : find_method("xpbd")->option(name)->fallback);
}

// the control a method runs: the sweep's substeps and iterations where it takes them (a row of the compliant rod
// sets them alike for every method, for its table)
StepControl taken_by(const std::string& method, StepControl control) {
  std::erase_if(control.settings, [m = find_method(method)](const auto& setting) { return !m->option(setting.first); });
  return control;
}

struct ConstrainedScene {
  std::string label, model;
  Params params;
  double t_end;
  double dt0;  // the ODE methods' coarsest step
};

struct Setting {
  size_t scene;
  std::string method, variant;
  StepControl control;
};

struct Outcome {
  std::string status;
  double error = NAN, drift = NAN, cpu_seconds = 0;
  long rhs_evals = 0;
  static auto fields(auto& s) { return std::tie(s.status, s.error, s.drift, s.cpu_seconds, s.rhs_evals); }
};

// the run of one setting: its error at t_end against `truth` (the whole state's max norm) and its largest drift
// | |x_a - x_b| - l | / l, sampled 100 times (a cloth's: at the end)
Outcome run_setting(const ConstrainedScene& scene, const Setting& s, const Eigen::VectorXd& truth) {
  const auto model = constrained(scene.model, scene.params, s.variant);
  const auto* constraints = model->as<DistanceConstraints>();
  const Measured m = run_and_measure(*model, s.method, taken_by(s.method, s.control), scene.t_end, scene.t_end / 100);
  Outcome o{std::string(to_string(m.result.status)), NAN, 0, m.result.stats.cpu_seconds, m.result.stats.rhs_evals};
  // the trajectory holds the whole state, or (a cloth) the model's summary of it: then the drift at the end alone
  if (model->summary_names().empty())
    for (const auto& y : m.result.trajectory.y) o.drift = std::max(o.drift, constraints->drift(y.data()));
  else
    o.drift = constraints->drift(m.result.y_stop.data());
  if (m.result.status == Status::ok) o.error = max_norm_error(m.result.y_stop, truth);
  return o;
}

// the settings of the work-precision sweep on one scene: the ODE methods halving their step from dt0, tsitouras54
// adaptive with projection, IDA on the DAE beside CVODE's BDF on the ODE form (the same method and error
// control), RATTLE, and xpbd turning each knob at a 1/60 s frame
std::vector<Setting> work_precision_settings(size_t scene, double dt0, bool quick) {
  std::vector<Setting> out;
  const int halvings = quick ? 4 : 6;
  for (int k = 0; k < halvings; ++k) {
    const StepControl c = StepControl::fixed(dt0 / std::pow(2.0, k));
    for (const char* variant : {"", "projection", "baumgarte"}) out.push_back({scene, "rk4", variant, c});
    out.push_back({scene, "rattle", "", c});
  }
  for (int k = 3; k <= (quick ? 6 : 10); ++k) {
    const StepControl c = StepControl::adaptive(std::pow(10.0, -k), std::pow(10.0, -k - 2));
    out.push_back({scene, "tsitouras54", "projection", c});
    out.push_back({scene, "ida", "", c});
    out.push_back({scene, "cvode-bdf", "", c});
  }
  for (int s = 1; s <= (quick ? 64 : 512); s *= 2) out.push_back({scene, "xpbd", "small steps", position_based(engine_frame, s, 1)});
  for (int i = 1; i <= (quick ? 16 : 64); i *= 4) out.push_back({scene, "xpbd", "iterations", position_based(engine_frame, 1, i)});
  return out;
}

// the scene's answer at t_end: its exact solution, or (the chain) verner98 at rtol 1e-10, which RATTLE's
// second-order convergence to it confirms (verification/tests/test_constraints.cpp)
Eigen::VectorXd truth_of(const ConstrainedScene& scene) {
  const auto model = make_model(scene.model, scene.params);
  if (model->has_exact()) return model->exact(scene.t_end);
  const Measured reference = run_and_measure(*model, "verner98", StepControl::adaptive(1e-10, 1e-12), scene.t_end, scene.t_end);
  if (reference.result.status != Status::ok) throw std::runtime_error("constraints: the chain's reference run failed: " + reference.result.message);
  return reference.result.y_stop;
}

// a method and how it keeps the constraints, as a line's legend names it: "rk4", "rk4 projection"
std::string label_of(const Setting& s) { return s.variant.empty() ? s.method : s.method + " " + s.variant; }

std::string mode_of(const StepControl& c) { return c.dt ? "fixed" : "adaptive"; }

Table work_precision_table(const StudyContext& ctx, const std::vector<ConstrainedScene>& scenes, const std::vector<Eigen::VectorXd>& truths,
                           std::vector<Setting> settings) {
  std::vector<std::string> labels;
  for (const auto& s : settings) labels.push_back(fmt::format("{} {} {}", scenes[s.scene].label, s.method, s.variant));
  const auto outcomes = ctx.sweep<Outcome>(labels, [&](size_t i) { return run_setting(scenes[settings[i].scene], settings[i], truths[settings[i].scene]); });
  Table t{{"scene", "method", "variant", "label", "mode", "dt", "rtol", "substeps", "iterations", "error", "drift", "cpu_seconds", "rhs_evals", "status"}, {}};
  for (size_t i = 0; i < settings.size(); ++i) {
    const Setting& s = settings[i];
    const Outcome& o = outcomes[i];
    t.rows.push_back({scenes[s.scene].label, s.method, s.variant, label_of(s), mode_of(s.control), s.control.dt.value_or(NAN), s.control.dt ? NAN : s.control.rtol,
                      knob(s.control, "substeps"), knob(s.control, "iterations"), o.error, o.drift, o.cpu_seconds, o.rhs_evals, o.status});
  }
  return t;
}

// the Cartesian pendulum over `periods` periods at dt = T/100, sampled once a period: each treatment's drift and
// relative energy error (E - E0) / (E0 - E_bottom); and in `ends`, each run's last sample, the periods it ran and
// how it ended (plain rk4's drift grows until the run diverges)
Table long_run_table(const StudyContext& ctx, double theta0, int periods, Table& ends) {
  const double period = pendulum_period(theta0, 9.81, 1.0), dt = period / 100;
  const Params params{{"theta0", theta0}};
  const std::vector<Setting> settings{{0, "rk4", "", StepControl::fixed(dt)},
                                      {0, "rk4", "projection", StepControl::fixed(dt)},
                                      {0, "rk4", "baumgarte", StepControl::fixed(dt)},
                                      {0, "rattle", "", StepControl::fixed(dt)},
                                      {0, "xpbd", "small steps", position_based(dt, 1, 1)}};
  std::vector<std::string> labels;
  for (const auto& s : settings) labels.push_back(s.method + " " + s.variant);
  const auto runs = ctx.sweep<RunResult>(labels, [&](size_t i) {
    const auto model = constrained("pendulum-cartesian", params, settings[i].variant);
    return run_and_measure(*model, settings[i].method, taken_by(settings[i].method, settings[i].control), periods * period, period).result;
  });
  const auto model = make_model("pendulum-cartesian", params);
  const auto* constraints = model->as<DistanceConstraints>();
  const double e0 = *model->energy(model->initial_state()), bottom = -9.81;  // m g y at the bottom, m = L = 1
  Table t{{"method", "variant", "label", "periods", "drift", "relative_energy_error"}, {}};
  ends = {{"method", "variant", "status", "periods", "drift", "relative_energy_error"}, {}};
  for (size_t i = 0; i < settings.size(); ++i) {
    for (size_t k = 0; k < runs[i].trajectory.y.size(); ++k) {
      const auto& y = runs[i].trajectory.y[k];
      t.rows.push_back({settings[i].method, settings[i].variant, label_of(settings[i]), long(k + 1), constraints->drift(y.data()), (*model->energy(y) - e0) / (e0 - bottom)});
    }
    const auto& last = t.rows.back();
    ends.rows.push_back({settings[i].method, settings[i].variant, std::string(to_string(runs[i].status)), last[3], last[4], last[5]});
  }
  return t;
}

// XPBD's artificial damping: the Cartesian pendulum (theta0 = 1) over 10 periods at a 1/60 s frame in more and more
// substeps, beside implicit Euler (projected) at the same substep and RATTLE: the energy above the bottom lost per
// period, 1 - (E_end - E_bottom)/(E0 - E_bottom))^(1/10)
Table damping_table(const StudyContext& ctx, bool quick) {
  const double theta0 = 1.0, period = pendulum_period(theta0, 9.81, 1.0);
  const int periods = 10;
  std::vector<Setting> settings;
  for (int s = 1; s <= (quick ? 32 : 128); s *= 2) {
    settings.push_back({0, "xpbd", "small steps", position_based(engine_frame, s, 1)});
    settings.push_back({0, "implicit-euler", "projection", StepControl::fixed(engine_frame / s)});
    settings.push_back({0, "rattle", "", StepControl::fixed(engine_frame / s)});
  }
  std::vector<std::string> labels;
  for (const auto& s : settings) labels.push_back(s.method);
  const Params params{{"theta0", theta0}};
  const auto ends = ctx.sweep<RunResult>(labels, [&](size_t i) {
    const auto model = constrained("pendulum-cartesian", params, settings[i].variant);
    RunResult r = run_and_measure(*model, settings[i].method, taken_by(settings[i].method, settings[i].control), periods * period, periods * period).result;
    r.trajectory = {};
    return r;
  });
  const auto model = make_model("pendulum-cartesian", params);
  const double e0 = *model->energy(model->initial_state()), bottom = -9.81;
  Table t{{"method", "variant", "label", "step", "energy_loss_per_period", "status"}, {}};
  for (size_t i = 0; i < settings.size(); ++i) {
    const double left = (*model->energy(ends[i].y_stop) - bottom) / (e0 - bottom);
    t.rows.push_back({settings[i].method, settings[i].variant, label_of(settings[i]), *settings[i].control.dt / knob(settings[i].control, "substeps"),
                      1 - std::pow(std::max(left, 0.0), 1.0 / periods), std::string(to_string(ends[i].status))});
  }
  return t;
}

// Macklin et al. (2019) measured: a scene at a 1/60 s frame with a budget of B constraint sweeps a frame, spent as
// s substeps of B/s iterations, for each s: the chain against its reference, and the seeds' 32 x 32 flag (its
// springs as compliant constraints) against xpbd's own converged answer, 1/60 s in `flag_reference` substeps of
// one iteration (first order in the substep: its own error 1/20 of the 16-substep point's, or less)
struct SubstepSubject {
  ConstrainedScene scene;
  Eigen::VectorXd truth;
  std::vector<int> budgets;
};
constexpr int flag_reference = 320;

SubstepSubject flag_subject(bool quick) {
  ConstrainedScene flag{"flag", "cloth", {}, quick ? 0.25 : 1.0, 0};
  const auto model = make_model("cloth", {});
  const Measured reference = run_and_measure(*model, "xpbd", position_based(engine_frame, flag_reference, 1), flag.t_end, flag.t_end);
  if (reference.result.status != Status::ok) throw std::runtime_error("constraints: the flag's reference run failed: " + reference.result.message);
  return {flag, reference.result.y_stop, {16}};
}

Table substeps_table(const StudyContext& ctx, const std::vector<SubstepSubject>& subjects) {
  std::vector<Setting> settings;
  std::vector<long> budgets;
  for (size_t k = 0; k < subjects.size(); ++k)
    for (const int budget : subjects[k].budgets)
      for (int s = 1; s <= budget; s *= 2) {
        settings.push_back({k, "xpbd", "", position_based(engine_frame, s, budget / s)});
        budgets.push_back(budget);
      }
  std::vector<std::string> labels;
  for (const auto& s : settings) labels.push_back(fmt::format("{} xpbd {}x{}", subjects[s.scene].scene.label, knob(s.control, "substeps"), knob(s.control, "iterations")));
  const auto outcomes = ctx.sweep<Outcome>(labels, [&](size_t i) { return run_setting(subjects[settings[i].scene].scene, settings[i], subjects[settings[i].scene].truth); });
  Table t{{"scene", "budget", "substeps", "iterations", "error", "drift", "cpu_seconds", "status"}, {}};
  for (size_t i = 0; i < settings.size(); ++i)
    t.rows.push_back({subjects[settings[i].scene].scene.label, budgets[i], knob(settings[i].control, "substeps"), knob(settings[i].control, "iterations"),
                      outcomes[i].error, outcomes[i].drift, outcomes[i].cpu_seconds, outcomes[i].status});
  return t;
}

// a stiffness set by compliance: a 1 kg mass hanging at rest on a rod of compliance 1e-3 m/N, a 1/60 s frame of one
// substep, for 1 s: its mean stretch over the last half against Hooke's m g alpha, for pbd and xpbd at each
// iteration count
Table stiffness_table(const StudyContext& ctx) {
  const double alpha = rod_compliance, hooke = hooke_stretch;
  std::vector<Setting> settings;
  for (int i = 1; i <= 64; i *= 2)
    for (const char* method : {"pbd", "xpbd"}) settings.push_back({0, method, "", position_based(engine_frame, 1, i)});
  std::vector<std::string> labels;
  for (const auto& s : settings) labels.push_back(fmt::format("{} {} iterations", s.method, knob(s.control, "iterations")));
  const auto runs = ctx.sweep<RunResult>(labels, [&](size_t i) {
    const auto model = make_model("pendulum-cartesian", {{"theta0", 0.0}, {"compliance", alpha}});
    return run_and_measure(*model, settings[i].method, taken_by(settings[i].method, settings[i].control), 1.0, engine_frame).result;
  });
  Table t{{"method", "iterations", "stretch", "hooke"}, {}};
  for (size_t i = 0; i < settings.size(); ++i) {
    const auto& ys = runs[i].trajectory.y;
    double sum = 0;
    const size_t half = ys.size() / 2;
    for (size_t k = half; k < ys.size(); ++k) sum += ys[k].head<2>().norm() - 1.0;
    t.rows.push_back({settings[i].method, knob(settings[i].control, "iterations"), sum / double(ys.size() - half), hooke});
  }
  return t;
}

// the compliant rod at an engine's frame: the Cartesian pendulum (theta0 = 1) on a rod of each compliance, 2 s of 1/60 s
// frames; each method's position at the end against backward Euler's converged step (implicit-euler-newton at the same
// frame, the answer vbd, xpbd and fast-mass-spring iterate towards) and against the rod's true motion (verner98 at rtol
// 1e-10): per-node Newton (vbd) and per-constraint projection (xpbd) at each iteration count, the linearised implicit
// Euler (one Newton step), the prefactored local/global method, and symplectic Euler (explicit: stable for omega h < 2)
constexpr std::array rod_compliances{1e-3, 1e-6};  // m/N
constexpr double rod_mass = 1.0;                    // kg: the pendulum's default bob
// the rod's omega h at a frame: h / sqrt(m alpha) (0.53 and 17 for the compliances above)
double rod_omega_h(double alpha) { return engine_frame / std::sqrt(rod_mass * alpha); }
constexpr double rod_t_end = 2.0;                   // s

struct RodOutcome {
  std::string status;
  double off_backward_euler = NAN, off_true_motion = NAN, cpu_seconds = 0;  // m, m, s
  static auto fields(auto& s) { return std::tie(s.status, s.off_backward_euler, s.off_true_motion, s.cpu_seconds); }
};

// the table (backward Euler's rows: its Newton iterations a frame, rounded up, and its distance from the true motion),
// and in `backward_euler_off` that distance at each compliance (m)
Table compliant_rod_table(const StudyContext& ctx, std::vector<double>& backward_euler_off) {
  const auto rod = [](double alpha) { return make_model("pendulum-cartesian", {{"theta0", 1.0}, {"mass", rod_mass}, {"compliance", alpha}}); };
  std::vector<Eigen::Vector2d> backward_euler, reference;
  std::vector<Stats> newton;
  for (const double alpha : rod_compliances)
    for (const auto& [method, control, into] : {std::tuple{"implicit-euler-newton", StepControl::fixed(engine_frame), &backward_euler},
                                                std::tuple{"verner98", StepControl::adaptive(1e-10, 1e-12), &reference}}) {
      const Measured m = run_and_measure(*rod(alpha), method, control, rod_t_end, rod_t_end);
      if (m.result.status != Status::ok) throw std::runtime_error(fmt::format("constraints: the compliant rod's {} run failed: {}", method, m.result.message));
      into->push_back(m.result.y_stop.head<2>());
      if (into == &backward_euler) newton.push_back(m.result.stats);
    }
  backward_euler_off.clear();
  for (size_t k = 0; k < rod_compliances.size(); ++k) backward_euler_off.push_back((backward_euler[k] - reference[k]).lpNorm<Eigen::Infinity>());
  std::vector<Setting> settings;
  for (size_t k = 0; k < rod_compliances.size(); ++k) {
    for (const int i : {1, 2, 5, 10})
      for (const char* method : {"xpbd", "vbd"}) settings.push_back({k, method, "", position_based(engine_frame, 1, i)});
    settings.push_back({k, "implicit-euler", "", position_based(engine_frame, 1, 1)});
    settings.push_back({k, "fast-mass-spring", "", position_based(engine_frame, 1, fast_mass_spring_iterations)});
    settings.push_back({k, "symplectic-euler", "", position_based(engine_frame, 1, 1)});
  }
  std::vector<std::string> labels;
  for (const auto& s : settings) labels.push_back(fmt::format("rod {:g} m/N {} {}", rod_compliances[s.scene], s.method, knob(s.control, "iterations")));
  const auto runs = ctx.sweep<RodOutcome>(labels, [&](size_t i) {
    const Setting& s = settings[i];
    const Measured m = run_and_measure(*rod(rod_compliances[s.scene]), s.method, taken_by(s.method, s.control), rod_t_end, rod_t_end);
    RodOutcome o{std::string(to_string(m.result.status)), NAN, NAN, m.result.stats.cpu_seconds};
    if (m.result.status == Status::ok) {
      o.off_backward_euler = (m.result.y_stop.head<2>() - backward_euler[s.scene]).lpNorm<Eigen::Infinity>();
      o.off_true_motion = (m.result.y_stop.head<2>() - reference[s.scene]).lpNorm<Eigen::Infinity>();
    }
    return o;
  });
  Table t{{"compliance", "method", "iterations", "off_backward_euler", "off_true_motion", "cpu_seconds", "status"}, {}};
  for (size_t i = 0; i < settings.size(); ++i)
    t.rows.push_back({rod_compliances[settings[i].scene], settings[i].method, knob(settings[i].control, "iterations"), runs[i].off_backward_euler,
                      runs[i].off_true_motion, runs[i].cpu_seconds, runs[i].status});
  for (size_t k = 0; k < rod_compliances.size(); ++k) {
    const long a_frame = (newton[k].newton_iterations + newton[k].steps - 1) / std::max(newton[k].steps, 1L);
    t.rows.push_back({rod_compliances[k], std::string("implicit-euler-newton"), a_frame, 0.0, backward_euler_off[k], newton[k].cpu_seconds, std::string("ok")});
  }
  return t;
}

// the hanging cloth (scenes/hanging-cloth.toml, 24 x 24) read as compliant constraints, a 1/60 s frame of one
// substep for 3 s: its sag (the drop of its mean height) averaged over the last second, for pbd and xpbd at each
// iteration count; and the spring model's own at rest (implicit Euler, 5 s at 0.01 s), the answer XPBD's
// Hooke's law converges to
const Params hanging_cloth{{"rows", 24}, {"columns", 24}, {"mass", 0.4}, {"stiffness", 200}, {"shear_stiffness", 100}, {"bend_stiffness", 10},
                           {"damping", 0.05}, {"drag", 0.1}, {"pin_top_corners", 1}, {"pin_corners", 0}, {"wind_coefficient", 0}};

Table sag_table(const StudyContext& ctx, bool quick, double& spring_sag) {
  std::vector<Setting> settings{{0, "implicit-euler", "", StepControl::fixed(0.01)}};
  for (int i = 1; i <= (quick ? 8 : 64); i *= 2)
    for (const char* method : {"pbd", "xpbd"}) settings.push_back({0, method, "", position_based(engine_frame, 1, i)});
  std::vector<std::string> labels;
  for (const auto& s : settings) labels.push_back(fmt::format("hanging cloth {} {}", s.method, s.method == "implicit-euler" ? "at rest" : fmt::format("{} iterations", knob(s.control, "iterations"))));
  const auto model = make_model("cloth", hanging_cloth);
  const auto names = model->summary_names();
  const auto mean_height = static_cast<Eigen::Index>(std::find(names.begin(), names.end(), "y_mean") - names.begin());
  const auto y_mean = [&](const Eigen::VectorXd& y) { return model->summary(y)[mean_height]; };
  const double rest = y_mean(model->initial_state());
  const auto sags = ctx.sweep<double>(labels, [&](size_t i) {
    const auto cloth = make_model("cloth", hanging_cloth);
    const bool spring = i == 0;
    const RunResult r = run_and_measure(*cloth, settings[i].method, taken_by(settings[i].method, settings[i].control), spring ? 5.0 : 3.0, spring ? 5.0 : engine_frame).result;
    if (r.status != Status::ok) return std::numeric_limits<double>::quiet_NaN();
    if (spring) return rest - y_mean(r.y_stop);
    double sum = 0;
    int n = 0;
    for (size_t k = 0; k < r.trajectory.t.size(); ++k)
      if (r.trajectory.t[k] > 2.0) sum += rest - r.trajectory.y[k][mean_height], ++n;  // the trajectory keeps the model's summary
    return sum / double(n);
  });
  spring_sag = sags[0];
  Table t{{"method", "iterations", "sag", "spring_model_sag"}, {}};
  for (size_t i = 1; i < settings.size(); ++i) t.rows.push_back({settings[i].method, knob(settings[i].control, "iterations"), sags[i], spring_sag});
  return t;
}

double number(const Table& t, const std::vector<Cell>& row, std::string_view column) {
  const Cell& c = cell_of(t, row, column);
  if (const long* n = std::get_if<long>(&c)) return double(*n);
  return std::get<double>(c);
}
std::string text(const Table& t, const std::vector<Cell>& row, std::string_view column) { return std::get<std::string>(cell_of(t, row, column)); }

// the cheapest setting of each (scene, method, variant) that reaches `target` at t_end: its CPU and error
Table cheapest_table(const Table& wp, double target) {
  std::map<std::tuple<std::string, std::string, std::string>, size_t> best;
  for (size_t r = 0; r < wp.rows.size(); ++r) {
    const auto& row = wp.rows[r];
    if (text(wp, row, "status") != "ok" || !(number(wp, row, "error") <= target)) continue;
    const auto key = std::tuple{text(wp, row, "scene"), text(wp, row, "method"), text(wp, row, "variant")};
    const auto it = best.find(key);
    if (it == best.end() || number(wp, row, "cpu_seconds") < number(wp, wp.rows[it->second], "cpu_seconds")) best[key] = r;
  }
  Table t{{"scene", "method", "variant", "setting", "error", "cpu_seconds"}, {}};
  for (const auto& [key, r] : best) {
    const auto& row = wp.rows[r];
    const std::string setting = text(wp, row, "mode") == "adaptive" ? fmt::format("rtol {:.0e}", number(wp, row, "rtol"))
                                : text(wp, row, "method") == "xpbd" ? fmt::format("{} substeps x {} iterations", number(wp, row, "substeps"), number(wp, row, "iterations"))
                                                                     : fmt::format("dt {:.3g} s", number(wp, row, "dt"));
    t.rows.push_back({std::get<0>(key), std::get<1>(key), std::get<2>(key), setting, number(wp, row, "error"), number(wp, row, "cpu_seconds")});
  }
  std::stable_sort(t.rows.begin(), t.rows.end(), [&](const auto& a, const auto& b) {
    return std::tie(std::get<std::string>(a[0]), std::get<double>(a[5])) < std::tie(std::get<std::string>(b[0]), std::get<double>(b[5]));
  });
  return t;
}

// the row of `t` where each named column holds the value given (the first), or null
const std::vector<Cell>* row_where(const Table& t, const std::vector<std::pair<std::string_view, Cell>>& match) {
  for (const auto& row : t.rows)
    if (std::all_of(match.begin(), match.end(), [&](const auto& m) { return cell_of(t, row, m.first) == m.second; })) return &row;
  return nullptr;
}

std::vector<Figure> figures_of(std::string& md, const std::string& stiffness_caption, double hooke, double spring_sag) {
  std::vector<Figure> figures;
  // a line per method and variant, each its own colour (rk4 plain, projected and stabilised apart): the series is
  // the label, not the method; fixed steps solid, tolerances dashed, failures crosses
  FigureSpec::Layer wp{.table = "constraints_work_precision", .x = "cpu_seconds", .y = "error", .series = "label", .failures = true,
                       .hover = {{"dt", "dt"}, {"rtol", "rtol"}, {"substeps", "substeps"}, {"iterations", "iterations"}, {"cpu_seconds", "CPU s"}}};
  FigureSpec::Layer wp_adaptive = wp;
  wp.where.push_back({"mode", {"fixed"}});
  wp_adaptive.where.push_back({"mode", {"adaptive"}});
  wp_adaptive.dashed = true;
  md += add_figure(figures, "constraints_work_precision", "",
                   {.title = "Error at t_end against CPU: ODE methods plain, projected and Baumgarte-stabilised, RATTLE and xpbd",
                    .panels = {{.title = "{scene}", .x_label = "CPU (s)", .y_label = "max-norm error at t_end", .log_x = true, .log_y = true, .layers = {wp, wp_adaptive}}},
                    .facet = {"scene"}},
                   "Work-precision of the constrained methods on the Cartesian pendulum and the chain");
  md += add_figure(figures, "constraints_drift", "",
                   {.title = "The Cartesian pendulum over many periods at dt = T/100",
                    .panels = {{.x_label = "periods", .y_label = "drift | |x| - L | / L", .log_y = true,
                                .layers = {{.table = "constraints_long_run", .x = "periods", .y = "drift", .series = "label", .mark = FigureMark::line, .floor = 1e-17}}},
                               {.x_label = "periods", .y_label = "|E - E0| / (E0 - E_bottom)", .log_y = true,
                                .layers = {{.table = "constraints_long_run", .x = "periods", .y = "relative_energy_error", .series = "label", .mark = FigureMark::line, .y_of = "abs", .floor = 1e-17}}}}},
                   "Drift from the constraint and energy error of each treatment over the long run");
  md += add_figure(figures, "constraints_substeps", "",
                   {.title = "A 1/60 s frame's budget of constraint sweeps spent as substeps x iterations",
                    .panels = {{.title = "{scene}", .x_label = "substeps (iterations = budget / substeps)", .y_label = "max-norm error at t_end", .log_x = true, .log_y = true,
                                .layers = {{.table = "constraints_substeps", .x = "substeps", .y = "error", .series = "budget", .label = "{} sweeps a frame"}}}},
                    .facet = {"scene"}},
                   "Substeps against iterations at equal cost (Macklin et al. 2019)");
  md += add_figure(figures, "constraints_damping", "",
                   {.title = "Energy lost per period by the Cartesian pendulum (theta0 = 1) against the (sub)step",
                    .panels = {{.x_label = "(sub)step (s)", .y_label = "energy lost per period", .log_x = true, .log_y = true,
                                .layers = {{.table = "constraints_damping", .x = "step", .y = "energy_loss_per_period", .series = "label", .floor = 1e-17}}}}},
                   "XPBD's artificial damping beside implicit Euler's, and RATTLE's none");
  md += add_figure(figures, "constraints_stiffness", "",
                   {.title = stiffness_caption,
                    .panels = {{.x_label = "iterations a frame", .y_label = "stretch (m)", .log_x = true,
                                .layers = {{.table = "constraints_stiffness", .x = "iterations", .y = "stretch", .series = "method"}},
                                .lines = {{'y', hooke, "Hooke: m g alpha"}}}}},
                   "PBD's stiffness moves with its iteration count; XPBD's does not");
  md += add_figure(figures, "constraints_sag", "",
                   {.title = "The hanging cloth's sag against the iterations a frame (its springs as compliant constraints)",
                    .panels = {{.x_label = "iterations a frame", .y_label = "sag of the mean height (m)", .log_x = true,
                                .layers = {{.table = "constraints_sag", .x = "iterations", .y = "sag", .series = "method"}},
                                .lines = {{'y', spring_sag, "the spring model at rest"}}}}},
                   "The hanging cloth's sag under pbd and xpbd against the iterations a frame");
  return figures;
}

// what the study measures: its tables, and the numbers its text names
struct Measurements {
  Table wp, cheapest, long_run, long_run_ends, damping, substeps, stiffness, sag, rod;
  double spring_sag = NAN;
  std::vector<double> rod_backward_euler_off;  // m, at each of rod_compliances
  int periods = 0;
};

constexpr double target = 1e-3;           // the error the cheapest table is for
constexpr double pendulum_t_end = 10.0;  // s: the Cartesian pendulum's run in the work-precision sweep

Measurements measure(const StudyContext& ctx) {
  const bool quick = ctx.quick;
  Measurements t;
  const std::vector<ConstrainedScene> scenes{{"pendulum-cartesian", "pendulum-cartesian", {{"theta0", 1.0}}, pendulum_t_end, 0.02},
                                             {"chain", "chain", {{"links", 20}}, 1.0, 0.004}};
  std::vector<Eigen::VectorXd> truths;
  for (const auto& s : scenes) truths.push_back(truth_of(s));
  std::vector<Setting> settings;
  for (size_t k = 0; k < scenes.size(); ++k)
    for (auto& s : work_precision_settings(k, scenes[k].dt0, quick)) settings.push_back(std::move(s));
  t.wp = work_precision_table(ctx, scenes, truths, std::move(settings));
  t.cheapest = cheapest_table(t.wp, target);
  t.periods = quick ? 100 : 1000;
  t.long_run = long_run_table(ctx, 1.0, t.periods, t.long_run_ends);
  t.damping = damping_table(ctx, quick);
  t.substeps = substeps_table(ctx, {{scenes[1], truths[1], quick ? std::vector<int>{8, 64} : std::vector<int>{8, 64, 512}}, flag_subject(quick)});
  t.stiffness = stiffness_table(ctx);
  t.rod = compliant_rod_table(ctx, t.rod_backward_euler_off);
  t.sag = sag_table(ctx, quick, t.spring_sag);
  return t;
}

// the section's text and tables, then its figures
std::string section(const Measurements& t, bool quick, std::vector<Figure>& figures) {
  std::string md = fmt::format(
      "The Cartesian pendulum (theta0 = 1 rad, {} s; its answer the reduced pendulum's exact theta(t)) and a chain of 20 rigid links "
      "released from the horizontal (1 s; its reference verner98 at rtol 1e-10, to which RATTLE converges at second order). The ODE "
      "methods step the constrained equations of motion plain (the constraint drifts with the method's error), with the state "
      "projected back after every step (`--constraint project`) or Baumgarte-stabilised (`--constraint baumgarte`); RATTLE is symplectic "
      "on the constraint manifold; xpbd (Macklin, Mueller & Chentanez 2016) steps a 1/60 s frame in substeps of Gauss-Seidel iterations.\n\n"
      "**The cheapest setting of each to reach a max-norm error of {:.0e} at t_end:**\n\n",
      pendulum_t_end, target);
  md += markdown_table(t.cheapest, {{"scene", "scene"}, {"method", "method"}, {"variant", "kept by"}, {"setting", "setting"},
                                  {"error", "error", shown_as("sci")}, {"cpu_seconds", "CPU (s)", shown_as("sci")}});
  md += fmt::format("\nOver {} periods at dt = T/100 (or until the run diverged), the drift from |x| = L and the energy error at the "
                    "last sample:\n\n", t.periods);
  md += markdown_table(t.long_run_ends, {{"method", "method"}, {"variant", "kept by"}, {"status", "run"}, {"periods", "periods"},
                                       {"drift", "drift", shown_as("sci")}, {"relative_energy_error", "energy error", shown_as("sci")}});
  md += fmt::format("\nMacklin et al. (2019)'s claim: a frame's budget of constraint sweeps spent as substeps of fewer iterations, on the "
                    "chain (against its reference at 1 s) and on the seeds' 32 x 32 flag (its springs as compliant constraints; against xpbd's own "
                    "answer at {} substeps of one iteration, at {} s):\n\n", flag_reference, quick ? 0.25 : 1.0);
  md += markdown_table(t.substeps, {{"scene", "scene"}, {"budget", "sweeps a frame"}, {"substeps", "substeps"}, {"iterations", "iterations"},
                                  {"error", "error", shown_as("sci")}, {"drift", "drift", shown_as("sci")}, {"cpu_seconds", "CPU (s)", shown_as("sci")}});
  md += "\nArtificial damping, the energy above the bottom lost per period over 10 periods:\n\n";
  md += markdown_table(t.damping, {{"method", "method"}, {"variant", "kept by"}, {"step", "(sub)step (s)", shown_as("{:.3g}")},
                                 {"energy_loss_per_period", "lost per period", shown_as("sci")}});
  md += fmt::format("\nA 1 kg mass hanging on a rod of compliance 1e-3 m/N (Hooke's stretch m g alpha = {:.3g} m), one substep of "
                    "1/60 s: its mean stretch over the last half second against the iterations a frame:\n\n", hooke_stretch);
  md += markdown_table(t.stiffness, {{"method", "method"}, {"iterations", "iterations"}, {"stretch", "stretch (m)", shown_as("{:.4g}")}});
  md += fmt::format("\nThe pendulum (theta0 = 1 rad, 1 kg) on a compliant rod, {} s of 1/60 s frames: each method's bob at the end, its distance from "
                    "backward Euler's converged step at the same frame (implicit-euler-newton: the answer vbd, xpbd and fast-mass-spring iterate towards) "
                    "and from the rod's true motion (verner98 at rtol 1e-10). A rod of {:.0e} m/N is stiff at a frame (omega h = h / sqrt(m alpha) = {:.2g}; "
                    "{:.0e} m/N: {:.2g}). "
                    "vbd and xpbd take the iterations a frame shown; implicit-euler is one Newton step, fast-mass-spring {} local/global iterations, "
                    "implicit-euler-newton as many as it needs (its rows: the mean a frame, rounded up):\n\n",
                    rod_t_end, rod_compliances[1], rod_omega_h(rod_compliances[1]), rod_compliances[0], rod_omega_h(rod_compliances[0]),
                    fast_mass_spring_iterations);
  md += markdown_table(t.rod, {{"compliance", "compliance (m/N)", shown_as("{:.0e}")}, {"method", "method"}, {"iterations", "iterations"},
                               {"off_backward_euler", "off backward Euler (m)", shown_as("sci")}, {"off_true_motion", "off the true motion (m)", shown_as("sci")},
                               {"cpu_seconds", "CPU (s)", shown_as("sci")}, {"status", "run"}});
  md += fmt::format("\nThe hanging cloth (24 x 24, its springs read as compliant constraints of the same stiffness), one substep of 1/60 s: "
                    "its sag over the third second against the iterations a frame, beside the spring model's at rest ({:.4g} m):\n\n", t.spring_sag);
  md += markdown_table(t.sag, {{"method", "method"}, {"iterations", "iterations"}, {"sag", "sag (m)", shown_as("{:.4g}")}});
  md += "\n";
  figures = figures_of(md, "The hanging mass's stretch against the iterations a frame (compliance 1e-3 m/N)", hooke_stretch, t.spring_sag);
  return md;
}

// what the section found, for the report's opening: a sentence each, its numbers as the tables show them
std::vector<std::string> findings_of(const Measurements& t, bool quick) {
  std::vector<std::string> findings;
  const auto end_of = [&](const char* method, const char* variant, const char* column) {
    const auto* row = row_where(t.long_run_ends, {{"method", std::string(method)}, {"variant", std::string(variant)}});
    return row ? shown_as("sci")(cell_of(t.long_run_ends, *row, column)) : std::string("-");
  };
  const auto* plain = row_where(t.long_run_ends, {{"method", std::string("rk4")}, {"variant", std::string()}});
  const std::string plain_end = plain && text(t.long_run_ends, *plain, "status") != "ok"
                                    ? fmt::format("drifts {} off its rod by period {} and then diverges", end_of("rk4", "", "drift"), number(t.long_run_ends, *plain, "periods"))
                                    : fmt::format("ends {} off its rod", end_of("rk4", "", "drift"));
  findings.push_back(fmt::format("**A constraint left to an ODE method drifts; kept, it does not**: over {} periods of the Cartesian pendulum at "
                                 "dt = T/100, rk4 on the constrained equations {}; with Baumgarte stabilisation it ends {} off, projected "
                                 "after each step {} and RATTLE {}, while xpbd at the same step keeps its rod and loses its swing (energy error {}: at rest).",
                                 t.periods, plain_end, end_of("rk4", "baumgarte", "drift"), end_of("rk4", "projection", "drift"), end_of("rattle", "", "drift"),
                                 end_of("xpbd", "small steps", "relative_energy_error")));
  const auto substep_error = [&](const char* scene, long budget, long s) {
    const auto* row = row_where(t.substeps, {{"scene", std::string(scene)}, {"budget", budget}, {"substeps", s}});
    return row ? number(t.substeps, *row, "error") : std::numeric_limits<double>::quiet_NaN();
  };
  findings.push_back(fmt::format("**Small steps win (Macklin et al. 2019), measured**: on the 20-link chain at a budget of 64 constraint sweeps a "
                                 "1/60 s frame, xpbd's error at 1 s is {} as 64 substeps of one iteration and {} as one substep of 64 iterations; "
                                 "on the 32 x 32 flag at 16 sweeps a frame, {} as 16 substeps and {} as one.",
                                 sci(substep_error("chain", 64, 64)), sci(substep_error("chain", 64, 1)), sci(substep_error("flag", 16, 16)),
                                 sci(substep_error("flag", 16, 1))));
  const auto damping_at = [&](const char* method, double step) {
    for (const auto& row : t.damping.rows)
      if (text(t.damping, row, "method") == method && std::abs(number(t.damping, row, "step") / step - 1) < 1e-9) return number(t.damping, row, "energy_loss_per_period");
    return std::numeric_limits<double>::quiet_NaN();
  };
  findings.push_back(fmt::format("**XPBD damps what it steps**: the Cartesian pendulum loses {} of its energy a period under xpbd at one 1/60 s "
                                 "substep, {} at 32 substeps, and {} under implicit Euler at 1/60 s; RATTLE loses {}.",
                                 sci(damping_at("xpbd", engine_frame)), sci(damping_at("xpbd", engine_frame / 32)), sci(damping_at("implicit-euler", engine_frame)), sci(damping_at("rattle", engine_frame))));
  const auto stretch_at = [&](const char* method, long iterations) {
    const auto* row = row_where(t.stiffness, {{"method", std::string(method)}, {"iterations", iterations}});
    return row ? number(t.stiffness, *row, "stretch") : std::numeric_limits<double>::quiet_NaN();
  };
  const auto sag_at = [&](const char* method, long iterations) {
    const auto* row = row_where(t.sag, {{"method", std::string(method)}, {"iterations", iterations}});
    return row ? number(t.sag, *row, "sag") : std::numeric_limits<double>::quiet_NaN();
  };
  const long most = quick ? 8 : 64;
  findings.push_back(fmt::format("**PBD's stiffness is its iteration count; XPBD's is the material's, once its iterations converge**: a mass on a rod "
                                 "of compliance 1e-3 m/N stretches {:.4g} m under xpbd at 1 and at 64 iterations a 1/60 s frame (Hooke: {:.3g} m) and "
                                 "under pbd from {:.4g} m to {:.4g} m; the 24 x 24 hanging cloth, whose {} constraints one sweep does not settle, "
                                 "sags {:.4g} m under xpbd at 1 iteration and {:.4g} m at {}, against the spring model's {:.4g} m at rest (pbd: {:.4g} m).",
                                 stretch_at("xpbd", 64), hooke_stretch, stretch_at("pbd", 1), stretch_at("pbd", 64),
                                 make_model("cloth", hanging_cloth)->as<DistanceConstraints>()->constraints.size(), sag_at("xpbd", 1), sag_at("xpbd", most), most,
                                 t.spring_sag, sag_at("pbd", most)));
  const auto rod_at = [&](size_t rod, const char* method, long iterations, const char* column) {
    const auto* row = row_where(t.rod, {{"compliance", rod_compliances[rod]}, {"method", std::string(method)}, {"iterations", iterations}});
    return row ? number(t.rod, *row, column) : std::numeric_limits<double>::quiet_NaN();
  };
  const auto* explicit_row = row_where(t.rod, {{"compliance", rod_compliances[1]}, {"method", std::string("symplectic-euler")}});
  const bool explicit_survived = explicit_row && text(t.rod, *explicit_row, "status") == "ok";
  findings.push_back(fmt::format("**On a stiff compliant rod at a frame step, one XPBD iteration is backward Euler's step; VBD needs two**: the pendulum "
                                 "on a rod of {:.0e} m/N (omega h = {:.0f} at 1/60 s) ends {} s {} m from converged backward Euler under xpbd at 1 iteration "
                                 "a frame, {} m under vbd at 1 sweep and {} m at 2; the linearised implicit Euler (one Newton step) ends {} m off and "
                                 "fast-mass-spring ({} local/global iterations) {} m; symplectic Euler {}. Converged backward Euler is itself {} m off "
                                 "the rod's true motion, and on a softer rod ({:.0e} m/N, omega h under 1) symplectic Euler, stable there, ends {} m off "
                                 "it where backward Euler ends {} m: at a frame step the error is backward Euler's damping, not its solver's.",
                                 rod_compliances[1], rod_omega_h(rod_compliances[1]), rod_t_end,
                                 sci(rod_at(1, "xpbd", 1, "off_backward_euler")), sci(rod_at(1, "vbd", 1, "off_backward_euler")),
                                 sci(rod_at(1, "vbd", 2, "off_backward_euler")), sci(rod_at(1, "implicit-euler", 1, "off_backward_euler")),
                                 fast_mass_spring_iterations, sci(rod_at(1, "fast-mass-spring", fast_mass_spring_iterations, "off_backward_euler")),
                                 explicit_survived ? "survives it" : "diverges (past its limit omega h = 2)", sci(t.rod_backward_euler_off[1]),
                                 rod_compliances[0], sci(rod_at(0, "symplectic-euler", 1, "off_true_motion")), sci(t.rod_backward_euler_off[0])));
  return findings;
}

StudyOutput constraints(const StudyContext& ctx) {
  Measurements t = measure(ctx);
  std::vector<Figure> figures;
  std::string md = section(t, ctx.quick, figures);
  std::vector<std::string> findings = findings_of(t, ctx.quick);
  return {{{"constraints_cheapest", std::move(t.cheapest)}, {"constraints_work_precision", std::move(t.wp)}, {"constraints_long_run", std::move(t.long_run)},
           {"constraints_long_run_ends", std::move(t.long_run_ends)}, {"constraints_substeps", std::move(t.substeps)},
           {"constraints_damping", std::move(t.damping)}, {"constraints_stiffness", std::move(t.stiffness)}, {"constraints_sag", std::move(t.sag)},
           {"constraints_compliant_rod", std::move(t.rod)}},
          md, figures, findings};
}

}  // namespace

Study constraints_study() { return {"constraints", "Constraints: projection, RATTLE and position-based dynamics", constraints}; }

}  // namespace stepwise
