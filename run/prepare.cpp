#include "prepare.hpp"

#include "projected_model.hpp"
#include "ranks.hpp"

#include "solvers/capabilities/distance_constraints.hpp"
#include "solvers/capabilities/mass_spring.hpp"
#include "solvers/method_table.hpp"
#include "solvers/run_support.hpp"
#include "solvers/stability.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <tuple>
#include <sys/statvfs.h>

namespace stepwise {
namespace {

// a whole string as a finite double, or nothing
std::optional<double> parse_number(std::string_view text) {
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

// a trajectory's bytes: a row of t, the columns and the energy, 17 significant digits and a sign, exponent and
// comma each (25 bytes a cell), and the header and first row
double trajectory_bytes(double rows, double columns) { return (rows + 2) * (columns + 2) * 25; }

void require_positive(std::optional<double> value, const std::string& where) {
  if (value && !(std::isfinite(*value) && *value > 0))
    throw InputError(fmt::format("{}: must be a positive finite number, got {}", where, *value));
}

}  // namespace

PreparedRun prepare_run(const RunOptions& o) { return prepare_run(o, load_scene(o.scene_file)); }

std::pair<std::string, std::string> default_method(const Model* model, double t_end, bool fixed_step) {
  if (fixed_step) return {"rk4", "no method named, a step given: rk4, the classical fixed-step method"};
  const auto decay = fastest_decay(*model, 0, model->initial_state());
  if (decay && t_end * *decay >= stiffness_threshold)
    return {"cvode-bdf", fmt::format("no method named: cvode-bdf (variable-order BDF), as the system is stiff at its start (t_end x fastest decay "
                                     "= {:.3g}, over {:g})", t_end * *decay, stiffness_threshold)};
  return {"tsitouras54", fmt::format("no method named: tsitouras54 (an adaptive 5(4) pair, as SciPy's RK45), as the system is {} (t_end x fastest "
                                     "decay{})", decay ? "not stiff at its start" : "taken as not stiff",
                                     decay ? fmt::format(" = {:.3g}, under {:g}", t_end * *decay, stiffness_threshold) : std::string(" not known: no Jacobian"))};
}

namespace {

// the scene's parameters with the --set overrides over them, and for each overridden key the option that set it
struct Values {
  Params values;
  std::map<std::string, std::string, std::less<>> set_origin;
  // where a key's value came from: "--set key", or the scene's parameters.key
  std::string where(const Scene& s, const std::string& key) const {
    const auto origin = set_origin.find(key);
    return origin != set_origin.end() ? origin->second : s.where("parameters." + key);
  }
};

Values overridden(const RunOptions& o, const Scene& s) {
  Values v{s.parameters, {}};
  for (const auto& set : o.sets) {
    const auto eq = set.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError(fmt::format("--set {}: expected key=value", set));
    const std::string key = set.substr(0, eq);
    const auto value = parse_number(set.substr(eq + 1));
    if (!value) throw InputError(fmt::format("--set {}: value '{}' is not a number", key, set.substr(eq + 1)));
    v.values[key] = *value;
    v.set_origin[key] = "--set " + key;
  }
  return v;
}

std::string where_method(const RunOptions& o, const Scene& s) { return o.method ? "--method" : s.where("run.method"); }

// a method's step control from the options over the scene's: adaptive (rtol, atol) where a tolerance is given, or
// no step is and the method adapts; else the fixed step, which a fixed-step method must be given. Checked by the
// method's own check, the one every way into a method goes through
StepControl step_control(const RunOptions& o, const Scene& s, const Method& method, StepControl control) {
  const bool adaptive = o.rtol || o.atol || (!o.dt && (!s.dt || !method.fixed_step()) && method.adaptive());
  if (adaptive) {
    control.rtol = o.rtol.value_or(s.rtol.value_or(control.rtol));
    control.atol = o.atol.value_or(s.atol.value_or(control.atol));
  } else {
    control.dt = o.dt ? o.dt : s.dt;
    if (!control.dt) throw InputError(fmt::format("{}: {} is a fixed-step method and neither --dt nor run.dt is given", s.file, method.name));
  }
  try {
    check_step_control(method, control);
  } catch (const BadMethod& e) {
    throw InputError(fmt::format("{}: {}", adaptive ? "--rtol" : "--dt", e.what()));
  }
  return control;
}
std::string where_dt(const RunOptions& o, const Scene& s) { return o.dt ? "--dt" : s.where("run.dt"); }

// the options' values on their own: each number in range, the names known, the step control a named method takes,
// and the budgets of steps and output rows. All before a model is made (a user's large system takes seconds to)
void check_options(const RunOptions& o, PreparedRun& p, std::exception_ptr& step_refused) {
  const Scene& s = p.scene;
  if (o.dt && (o.rtol || o.atol)) throw InputError("--dt: give either --dt or --rtol/--atol, not both");
  require_positive(o.dt, "--dt");
  require_positive(o.rtol, "--rtol");
  require_positive(o.atol, "--atol");
  require_positive(o.t_end, "--t-end");
  require_positive(o.output_dt, "--output-dt");
  require_positive(s.dt, s.where("run.dt"));
  require_positive(s.rtol, s.where("run.rtol"));
  require_positive(s.atol, s.where("run.atol"));
  require_positive(s.t_end, s.where("run.t_end"));
  require_positive(s.output_dt, s.where("run.output_dt"));
  // a relative tolerance of 1 or more asks for no digit at all
  for (const auto& [value, where] : {std::pair{o.rtol, std::string("--rtol")}, std::pair{s.rtol, s.where("run.rtol")}})
    if (value && *value >= 1) throw InputError(fmt::format("{}: a relative tolerance must be below 1, got {}", where, *value));
  const std::string location = o.event_location.value_or(s.event_location.value_or("linear"));
  if (location == "restep") p.control.event_location = EventLocation::restep;
  else if (location != "linear")
    throw InputError(fmt::format("{}: event location '{}' is neither linear nor restep",
                                 o.event_location ? "--event-location" : s.where("run.event_location"), location));
  const double max_steps = o.max_steps.value_or(default_max_steps);
  if (o.max_steps && !(max_steps >= 1 && max_steps <= 1e15 && std::floor(max_steps) == max_steps))
    throw InputError(fmt::format("--max-steps {}: must be a whole number in 1..1e15", max_steps));
  p.control.max_steps = static_cast<long>(max_steps);
  p.t_end = o.t_end.value_or(s.t_end.value_or(10.0));
  // the method where the inputs name it, or a step does (rk4); else it is chosen once the model is made
  if (o.method || s.method) {
    p.method = o.method ? *o.method : *s.method;
    if (!find_method(p.method)) throw InputError(fmt::format("{}: unknown method '{}' (see `stepwise methods`)", where_method(o, s), p.method));
  } else if (o.dt || s.dt) {
    std::tie(p.method, p.method_choice) = default_method(nullptr, p.t_end, true);
  }
  if (o.constraint && *o.constraint != "project" && *o.constraint != "baumgarte")
    throw InputError(fmt::format("--constraint {}: the constraint treatments are project (the state put back on the constraints after each step) "
                                 "and baumgarte (the equations of motion pulling any drift back)", *o.constraint));
  // the method's own options (its registration's: a position-based or vbd method's substeps and iterations, vbd's
  // threads, vbd-chebyshev's rate): each one the method takes, in its range
  const Method* method = p.method.empty() ? nullptr : find_method(p.method);
  for (const auto& [name, text] : o.method_options) {
    const MethodOption* option = method ? method->option(name) : nullptr;
    if (!option) {
      std::vector<std::string> takers;
      for (const auto& m : methods())
        if (m.option(name)) takers.emplace_back(m.name);
      throw InputError(fmt::format("--{}: {} takes no --{} ({} do{})", name, method ? p.method : "the method chosen for this scene", name,
                                   fmt::join(takers, ", "), takers.size() == 1 ? "es" : ""));
    }
    try {
      p.control.settings[name] = option->parse(text);
    } catch (const BadMethod& e) {
      throw InputError(fmt::format("--{} {}: {}", name, text, e.what()));
    }
  }
  // the step: the method's control, told now wherever the method is (a method chosen later is adaptive). A
  // method that needs a capability of the model (vbd: a mass-spring system) may not apply to it at all: that
  // reason comes first, so a step it lacks is said once the model is made (choose_method)
  if (!p.method.empty()) {
    try {
      p.control = step_control(o, s, *method, p.control);
    } catch (const InputError&) {
      if (!method->needs.type) throw;
      step_refused = std::current_exception();
    }
  }
  const double dt = p.control.dt.value_or(0);
  if (dt > p.t_end) throw InputError(fmt::format("{}: dt = {} is larger than t_end = {}", where_dt(o, s), dt, p.t_end));
  const auto where_t_end = [&] { return o.t_end ? std::string("--t-end") : s.t_end ? s.where("run.t_end") : std::string("t_end"); };
  if (dt > 0)
    if (const double steps = std::ceil(p.t_end / dt * (1 - 1e-12)); steps > max_steps)
      throw InputError(fmt::format("{} and {}: t_end / dt = {:.3g} steps, more than the {:.3g} allowed: take a larger step or a shorter run, "
                                   "or raise the limit with --max-steps", where_dt(o, s), where_t_end(), steps, max_steps));
  // the output rows: a fixed-step run samples on its own step grid (an output time between grid points would
  // shorten a step and change the very run being sampled: a dt beyond the stability limit would be hidden by short
  // steps); rounded first, so that the rows counted are the rows written (an output step of 1e-16 at dt = 1e-3 is
  // one row a step, not 1e13 rows). A run that turns out adaptive samples at the output step as given
  p.output_dt_origin = o.output_dt ? std::string("--output-dt") : s.output_dt ? s.where("run.output_dt") : std::string("the default output step (t_end / 1000)");
  p.output_dt = o.output_dt.value_or(s.output_dt.value_or(p.t_end / 1000));
  const double rows = std::floor(p.t_end / (dt > 0 ? std::max(1.0, std::round(p.output_dt / dt)) * dt : p.output_dt));
  if (rows > max_steps)
    throw InputError(fmt::format("{}: t_end / output_dt = {:.3g} output rows, more than the {:.3g} allowed: sample less often, or raise "
                                 "the limit with --max-steps", p.output_dt_origin, rows, max_steps));
}

// the trajectory's size before a model whose size its parameters set is made: at least the rows an output step
// gives once rounded to a fixed step (at most 1.5 times longer) times its columns, against the space where it goes
void check_output_before_model(const RunOptions& o, const PreparedRun& p, const ModelInfo& info, const Params& values) {
  if (!info.output_columns || o.out.empty()) return;
  try {
    const double columns = info.output_columns(resolve_params(info, values));
    const double at_least = trajectory_bytes(std::floor(p.t_end / (1.5 * p.output_dt)), columns);
    if (const auto free_bytes = free_bytes_at(o.out); free_bytes && at_least > *free_bytes)
      throw InputError(fmt::format("{}: the trajectory, a row every {:g} s of {:.0f} columns, would take at least {:.3g} GB, more than the {:.3g} GB "
                                   "free in {}: sample less often (--output-dt)",
                                   p.output_dt_origin, p.output_dt, columns + 2, at_least / 1e9, *free_bytes / 1e9, o.out));
  } catch (const BadParameter&) {
    // the model's own check names it
  }
}

// the model, from the scene's equations or the table of built-in models, with the values applied
void make_model(const RunOptions& o, PreparedRun& p, Values v) {
  const Scene& s = p.scene;
  const ModelInfo* info = s.equations || s.pde ? nullptr : find_model(s.model);
  // --constraint baumgarte: the constrained models' own flag (models/pendulum_cartesian.hpp, models/chain.hpp)
  if (o.constraint == "baumgarte") {
    if (!info || std::none_of(info->params.begin(), info->params.end(), [](const ParamSpec& q) { return q.key == "baumgarte"; }))
      throw InputError(fmt::format("--constraint: the scene has no rigid constraints to keep (model {}; pendulum-cartesian and chain have)", s.model));
    v.values["baumgarte"] = 1;
    v.set_origin["baumgarte"] = "--constraint baumgarte";
  }
  if (!info && !s.equations && !s.pde) throw InputError(fmt::format("{}: unknown model '{}' (see `stepwise scenes`)", s.where("model"), s.model));
  if (s.mesh && (!info || !info->make_with_mesh)) throw InputError(fmt::format("{}: model {} takes no mesh", s.where("mesh"), s.model));
  if (s.pins && (!info || !info->make_with_pins)) throw InputError(fmt::format("{}: model {} takes no pins", s.where("pins"), s.model));
  if (info) check_output_before_model(o, p, *info, v.values);
  try {
    if (s.pde) {
      // the user's PDE: its parameters by name, and the grid's points and order, --set on any
      p.model = make_pde(*s.pde, v.values);
      p.params = s.pde->parameters;
      for (const auto& [key, value] : v.values) p.params[key] = value;
    } else if (s.equations) {
      // the user's equations: parameters and initial values by name, --set on either (models/equations.hpp)
      p.model = make_equations(*s.equations, v.values);
      p.params = s.equations->parameters;
      for (const auto& [key, value] : s.equations->initial) p.params[key] = value;
      for (const auto& [key, value] : v.values) p.params[key] = value;
    } else {
      p.params = resolve_params(*info, v.values);
      p.model = s.mesh ? info->make_with_mesh(p.params, *s.mesh) : s.pins ? info->make_with_pins(p.params, *s.pins) : info->make(p.params);
    }
  } catch (const BadEquations& e) {
    throw InputError(e.what());
  } catch (const BadParameter& e) {
    throw InputError(fmt::format("{}: {}", e.key == "mesh" ? s.where("mesh") : e.key == "pins" ? s.where("pins") : v.where(s, e.key), e.what()));
  }
}

// a state that overflows from the start (a speed of 1e200 m/s squares to infinity) is refused, not run
void check_initial_state(const PreparedRun& p, const Values& v) {
  const Scene& s = p.scene;
  const Eigen::VectorXd y0 = p.model->initial_state();
  if (!y0.allFinite()) throw InputError(fmt::format("{}: the parameters give a non-finite initial state", s.where("parameters")));
  if (const auto e0 = p.model->energy(y0); e0 && !std::isfinite(*e0))
    throw InputError(fmt::format("{}: the parameters give an initial energy that overflows ({})", s.where("parameters"), *e0));
  // the blow-up test compares |y| with blowup x max(1, |y0|): a start so large that the bound overflows (an angle
  // of 1e308) could never be seen to diverge, and ran to `ok` with an error of 1e308. Refused, naming the
  // parameter that gave the entry where one did (else the state entry)
  Eigen::Index at = 0;
  const double largest = y0.size() ? y0.cwiseAbs().maxCoeff(&at) : 0.0;
  if (const StepControl control{}; !std::isfinite(divergence_bound(control, largest))) {
    std::string where = s.where("parameters");
    for (const auto& [key, value] : v.values)
      if (std::abs(value) == largest) where = v.where(s, key);
    const auto names = p.model->state_names();
    throw InputError(fmt::format("{}: the initial {} = {:g} is too large for a run to tell divergence from it (the blow-up test at {:g} "
                                 "x |y0| overflows above |y0| = {:.3g})",
                                 where, at < static_cast<Eigen::Index>(names.size()) ? names[static_cast<size_t>(at)] : "state", y0[at],
                                 control.blowup, std::numeric_limits<double>::max() / control.blowup));
  }
}

// the method (named, or chosen for the model: default_method) and its step control: the command line wins over
// the scene. Then what the method asks of the model: memory, time, what it applies to, its device
void choose_method(const RunOptions& o, PreparedRun& p, const std::exception_ptr& step_refused) {
  const Scene& s = p.scene;
  if (p.method.empty()) {
    std::tie(p.method, p.method_choice) = default_method(p.model.get(), p.t_end, false);
    p.control = step_control(o, s, *find_method(p.method), p.control);
  }
  const Method* method = find_method(p.method);
  const std::string sparse_hint = p.model->as<SparseJacobian>() ? " or cvode-bdf (sparse Jacobian, KLU)" : "";
  if (const double bytes = dense_matrix_bytes(*method, *p.model); over_memory_budget(bytes))
    throw InputError(fmt::format("{}: {} keeps dense {} x {} matrices ({:.3g} GiB) for this {}-entry state, {}: use an explicit method{}",
                                 where_method(o, s), p.method, p.model->size(), p.model->size(), bytes / 0x1p30, p.model->size(),
                                 memory_budget_text(), sparse_hint));
  // and the time: a dense LU of the Newton matrix takes (2/3) n^3 flops, at least once per step; past 1e12 (a
  // minute or more on one core here) a run of any length takes hours
  if (const double n = p.model->size(); dense_matrix_bytes(*method, *p.model) > 0 && 2.0 / 3.0 * n * n * n > 1e12)
    throw InputError(fmt::format("{}: {} factorises a dense {} x {} Newton matrix, {:.2g} flops each time (at least once a step): "
                                 "too slow to run; use an explicit method{}", where_method(o, s), p.method, p.model->size(), p.model->size(),
                                 2.0 / 3.0 * n * n * n, sparse_hint));
  if (!method_applies(*method, *p.model))
    throw InputError(fmt::format("{}: {} (model {})", where_method(o, s), method_requirement(*method, *p.model), s.model));
  if (step_refused) std::rethrow_exception(step_refused);
  // a method with a device of its own (a GPU method: its grid must be a texture the device renders to) is asked
  if (method->device_problem)
    if (const std::string problem = method->device_problem(*p.model); !problem.empty())
      throw InputError(fmt::format("{}: {}: {}", where_method(o, s), p.method, problem));
}

// a step past the method's stability limit is the user's to try: said (once: by rank 0 under mpirun), then run,
// and reported diverged
void warn_past_stability(const RunOptions& o, const PreparedRun& p) {
  if (!p.control.dt || ranks::rank() != 0) return;
  const Scene& s = p.scene;
  const Method& method = *find_method(p.method);
  if (const auto* grid = p.model->as<WaveGridView>(); grid && method.stability.wave_dt)
    if (const double limit = method.stability.wave_dt(*grid); *p.control.dt > limit)
      fmt::print(stderr, "{}: warning: dt = {} s is past {}'s stability limit {:.6g} s on this grid (d = {} m, c = {} m/s, "
                 "mu = {} 1/s); running it anyway\n", where_dt(o, s), *p.control.dt, p.method, limit, grid->spacing, grid->c, grid->mu);
  // and on a mass-spring system, the limit its stiffest mode sets at the start (verification/stability.hpp), for
  // the methods that have one (asked first with any mode, so the eigenproblem is solved only for those)
  if (p.model->as<MassSpringView>() && method.stability.oscillator_dt) {
    const StiffestMode mode = stiffest_mode(*p.model, 0, p.model->initial_state());
    if (const double limit = method.stability.oscillator_dt(mode.omega, mode.damping); *p.control.dt > limit)
      fmt::print(stderr, "{}: warning: dt = {} s is past {}'s stability limit {:.6g} s for this system's stiffest mode (omega = {:.6g} "
                 "rad/s, damping {:.3g} 1/s at the start); running it anyway\n", where_dt(o, s), *p.control.dt, p.method,
                 limit, mode.omega, mode.damping);
  }
}

}  // namespace

PreparedRun prepare_run(const RunOptions& o, Scene scene) {
  PreparedRun p;
  p.scene = std::move(scene);
  std::exception_ptr step_refused;
  check_options(o, p, step_refused);
  const Values values = overridden(o, p.scene);
  make_model(o, p, values);
  check_initial_state(p, values);
  choose_method(o, p, step_refused);
  if (o.constraint) {
    // an ODE method kept on a constrained scene's constraints; the constrained methods keep them themselves
    if (const auto* c = p.model->as<DistanceConstraints>(); !c || c->rigid().constraints.empty())
      throw InputError(fmt::format("--constraint: the scene has no rigid constraints to keep (model {}; pendulum-cartesian and chain have; "
                                   "a compliant constraint is a spring)", p.scene.model));
    if (find_method(p.method)->needs.type == &typeid(DistanceConstraints))
      throw InputError(fmt::format("--constraint: {} keeps the constraints itself", p.method));
    if (*o.constraint == "project") p.model = projected(std::move(p.model));
    p.constraint = *o.constraint;
  }
  warn_past_stability(o, p);
  // the trajectory: the output step on the step grid of a fixed-step run (check_options), rows times columns
  if (p.control.dt) p.output_dt = std::max(1.0, std::round(p.output_dt / *p.control.dt)) * *p.control.dt;
  double columns = static_cast<double>(p.model->summary_names().empty() ? p.model->state_names().size() : p.model->summary_names().size());
  if (const PdeGrid* grid = pde_grid(*p.model)) columns += static_cast<double>(grid->nodes()) * static_cast<double>(grid->fields.size());  // field_NAME.csv
  p.output_bytes = trajectory_bytes(std::floor(p.t_end / p.output_dt), columns);
  return p;
}

std::optional<double> free_bytes_at(const std::string& path) {
  std::filesystem::path at = std::filesystem::absolute(path).lexically_normal();
  for (;;) {
    struct statvfs fs {};
    if (::statvfs(at.c_str(), &fs) == 0) return static_cast<double>(fs.f_bavail) * static_cast<double>(fs.f_frsize);
    if (errno != ENOENT || !at.has_relative_path()) return std::nullopt;
    at = at.parent_path();
  }
}

void check_output_fits(const std::string& out, const PreparedRun& p) {
  const auto free_bytes = free_bytes_at(out);
  if (!free_bytes) return;  // unknown: the write itself will say
  if (p.output_bytes > *free_bytes)
    throw InputError(fmt::format("{}: the trajectory, a row every {:g} s, would take about {:.3g} GB, more than the {:.3g} GB free in {}: "
                                 "sample less often (--output-dt)", p.output_dt_origin, p.output_dt, p.output_bytes / 1e9, *free_bytes / 1e9, out));
}

}  // namespace stepwise
