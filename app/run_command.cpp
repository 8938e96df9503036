#include "run_command.hpp"

#include "report/atomic_write.hpp"
#include "report/csv.hpp"
#include "scene.hpp"
#include "verification/measure.hpp"
#include "solvers/capabilities/mass_spring.hpp"
#include "verification/stability.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <iostream>

namespace stepwise {
namespace {

// a whole string as a finite double, or nothing
std::optional<double> parse_number(std::string_view text) {
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

void require_positive(std::optional<double> value, const std::string& where) {
  if (value && !(std::isfinite(*value) && *value > 0))
    throw InputError(fmt::format("{}: must be a positive finite number, got {}", where, *value));
}

}  // namespace

PreparedRun prepare_run(const RunOptions& o) {
  PreparedRun p;
  p.scene = load_scene(o.scene_file);
  Scene& s = p.scene;

  // parameters: the scene's, then --set overrides
  Params values = s.parameters;
  std::map<std::string, std::string, std::less<>> set_origin;
  for (const auto& set : o.sets) {
    const auto eq = set.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError(fmt::format("--set {}: expected key=value", set));
    const std::string key = set.substr(0, eq);
    const auto value = parse_number(set.substr(eq + 1));
    if (!value) throw InputError(fmt::format("--set {}: value '{}' is not a number", key, set.substr(eq + 1)));
    values[key] = *value;
    set_origin[key] = "--set " + key;
  }
  const ModelInfo* info = find_model(s.model);
  if (!info) throw InputError(fmt::format("{}: unknown model '{}' (see `stepwise scenes`)", s.where("model"), s.model));
  if (s.mesh && !info->make_with_mesh) throw InputError(fmt::format("{}: model {} takes no mesh", s.where("mesh"), s.model));
  if (s.pins && !info->make_with_pins) throw InputError(fmt::format("{}: model {} takes no pins", s.where("pins"), s.model));
  try {
    p.params = resolve_params(*info, values);
    p.model = s.mesh ? info->make_with_mesh(p.params, *s.mesh) : s.pins ? info->make_with_pins(p.params, *s.pins) : info->make(p.params);
  } catch (const BadParameter& e) {
    const auto origin = set_origin.find(e.key);
    throw InputError(fmt::format("{}: {}", origin != set_origin.end() ? origin->second
                                           : e.key == "mesh"             ? s.where("mesh")
                                           : e.key == "pins"             ? s.where("pins")
                                                                         : s.where("parameters." + e.key),
                                 e.what()));
  }

  // method and step control: the command line wins over the scene; --dt and --rtol exclude each other
  p.method = o.method.value_or(s.method.value_or("rk4"));
  const Method* method = find_method(p.method);
  if (!method) throw InputError(fmt::format("{}: unknown method '{}' (see `stepwise methods`)", o.method ? "--method" : s.where("run.method"), p.method));
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

  const bool adaptive = o.rtol || o.atol || (!o.dt && (!s.dt || !method->fixed_step()) && method->adaptive());
  if (adaptive) {
    if (!method->adaptive()) throw InputError(fmt::format("--rtol: {} is a fixed-step method: give --dt", p.method));
    p.control.rtol = o.rtol.value_or(s.rtol.value_or(p.control.rtol));
    p.control.atol = o.atol.value_or(s.atol.value_or(p.control.atol));
  } else {
    p.control.dt = o.dt ? o.dt : s.dt;
    if (!p.control.dt) throw InputError(fmt::format("{}: {} is a fixed-step method and neither --dt nor run.dt is given", s.file, p.method));
    if (!method->fixed_step()) throw InputError(fmt::format("--dt: {} is adaptive only: give --rtol/--atol", p.method));
  }
  if (const double bytes = dense_matrix_bytes(*method, *p.model); bytes > 0.5 * physical_memory_bytes())
    throw InputError(fmt::format("{}: {} keeps dense {} x {} matrices ({:.3g} GiB) for this {}-entry state, more than half this "
                                 "machine's memory: use an explicit method{}",
                                 o.method ? "--method" : s.where("run.method"), p.method, p.model->size(), p.model->size(),
                                 bytes / 0x1p30, p.model->size(),
                                 p.model->has_sparse_jacobian() ? " or cvode-bdf (sparse Jacobian, KLU)" : ""));
  if (!method_applies(*method, *p.model))
    throw InputError(fmt::format("{}: {} (model {})", o.method ? "--method" : s.where("run.method"), method_requirement(*method, *p.model), s.model));
  // a method with a device of its own (a GPU method: its grid must be a texture the device renders to) is asked
  if (method->device_problem)
    if (const std::string problem = method->device_problem(*p.model); !problem.empty())
      throw InputError(fmt::format("{}: {}: {}", o.method ? "--method" : s.where("run.method"), p.method, problem));

  const std::string location = o.event_location.value_or(s.event_location.value_or("linear"));
  if (location == "restep") p.control.event_location = EventLocation::restep;
  else if (location != "linear")
    throw InputError(fmt::format("{}: event location '{}' is neither linear nor restep",
                                 o.event_location ? "--event-location" : s.where("run.event_location"), location));

  p.t_end = o.t_end.value_or(s.t_end.value_or(10.0));
  if (p.control.dt && *p.control.dt > p.t_end)
    throw InputError(fmt::format("{}: dt = {} is larger than t_end = {}", o.dt ? "--dt" : s.where("run.dt"), *p.control.dt, p.t_end));
  // a step past the method's stability limit is the user's to try: said, then run, and reported diverged
  if (const auto* grid = p.model->as<WaveGridView>(); grid && p.control.dt && method->stability.wave_dt)
    if (const double limit = method->stability.wave_dt(*grid); *p.control.dt > limit)
      fmt::print(stderr, "{}: warning: dt = {} s is past {}'s stability limit {:.6g} s on this grid (d = {} m, c = {} m/s, "
                 "mu = {} 1/s); running it anyway\n", o.dt ? "--dt" : s.where("run.dt"), *p.control.dt, p.method, limit,
                 grid->spacing, grid->c, grid->mu);
  // and on a mass-spring system, the limit its stiffest mode sets at the start (verification/stability.hpp), for
  // the methods that have one (asked first with any mode, so the eigenproblem is solved only for those)
  if (p.model->as<MassSpringView>() && p.control.dt && method->stability.oscillator_dt) {
    const StiffestMode mode = stiffest_mode(*p.model, 0, p.model->initial_state());
    if (const double limit = method->stability.oscillator_dt(mode.omega, mode.damping); *p.control.dt > limit)
      fmt::print(stderr, "{}: warning: dt = {} s is past {}'s stability limit {:.6g} s for this system's stiffest mode (omega = {:.6g} "
                 "rad/s, damping {:.3g} 1/s at the start); running it anyway\n", o.dt ? "--dt" : s.where("run.dt"), *p.control.dt, p.method,
                 limit, mode.omega, mode.damping);
  }
  p.output_dt = o.output_dt.value_or(s.output_dt.value_or(p.t_end / 1000));
  // a fixed-step run samples on its own step grid: an output time between grid points would shorten a step
  // and change the very run being sampled (a dt beyond the stability limit would be hidden by short steps)
  if (p.control.dt) p.output_dt = std::max(1.0, std::round(p.output_dt / *p.control.dt)) * *p.control.dt;
  return p;
}

namespace {

// columns: the state's names, or the model's summary of a large state; energy beside them where it exists
std::vector<std::string> sample_names(const Model& model) {
  auto names = model.summary_names();
  return names.empty() ? model.state_names() : names;
}

std::string trajectory_csv(const Model& model, const Measured& m) {
  Table table;
  table.columns.push_back("t");
  for (const auto& name : sample_names(model)) table.columns.push_back(name);
  const bool summarised = !model.summary_names().empty();
  const bool with_energy = !summarised && model.energy(model.initial_state()).has_value();
  if (with_energy) table.columns.push_back("energy");
  // a recorded sample is the state itself (energy computed from it), or already the model's summary of it
  auto add_row = [&](double t, const Eigen::VectorXd& sample) {
    std::vector<Cell> row{t};
    for (const double v : sample) row.emplace_back(v);
    if (with_energy) row.emplace_back(*model.energy(sample));
    table.rows.push_back(std::move(row));
  };
  add_row(0.0, model.summary(model.initial_state()));
  for (size_t i = 0; i < m.result.trajectory.t.size(); ++i) add_row(m.result.trajectory.t[i], m.result.trajectory.y[i]);
  if (m.result.status != Status::ok) add_row(m.result.t_stop, model.summary(m.result.y_stop));
  return to_csv(table);
}

nlohmann::json summary_json(const PreparedRun& p, const Measured& m) {
  const RunResult& r = m.result;
  nlohmann::json j;
  j["scene"] = p.scene.name;
  j["scene_file"] = p.scene.file;
  j["model"] = std::string(p.model->name());
  j["method"] = p.method;
  j["status"] = std::string(to_string(r.status));
  j["message"] = r.message.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.message);
  j["t_end"] = p.t_end;
  j["t_stop"] = r.status == Status::ok ? p.t_end : r.t_stop;
  if (p.control.dt) j["dt"] = *p.control.dt;
  else { j["rtol"] = p.control.rtol; j["atol"] = p.control.atol; }
  j["steps"] = r.stats.steps;
  j["rejected"] = r.stats.rejected;
  j["rhs_evals"] = r.stats.rhs_evals;
  j["jac_evals"] = r.stats.jac_evals;
  j["linear_solves"] = r.stats.linear_solves;
  j["factorizations"] = r.stats.factorizations;
  j["projections"] = r.stats.projections;
  j["contact_sweeps"] = r.stats.contact_sweeps;
  j["cpu_seconds"] = r.stats.cpu_seconds;
  const auto names = sample_names(*p.model);
  const Eigen::VectorXd final_sample = p.model->summary(r.y_stop);
  j["final_state"] = nlohmann::json::object();
  for (size_t i = 0; i < names.size(); ++i) j["final_state"][names[i]] = final_sample[static_cast<Eigen::Index>(i)];
  j["error"] = m.error ? nlohmann::json(*m.error) : nlohmann::json(nullptr);
  if (const auto e0 = p.model->energy(p.model->initial_state())) {
    j["energy_initial"] = *e0;
    j["energy_final"] = *p.model->energy(r.y_stop);
  }
  j["events"] = nlohmann::json::array();
  const auto events = p.model->events();
  for (const auto& e : r.events)
    j["events"].push_back({{"t", e.t}, {"kind", e.kind}, {"event", e.event < events.size() ? events[e.event].name : "contacts"}});
  j["parameters"] = nlohmann::json::object();
  for (const auto& [key, value] : p.params) j["parameters"][key] = value;
  return j;
}

}  // namespace

int run_command(const RunOptions& options) {
  PreparedRun p;
  try {
    p = prepare_run(options);
    ensure_writable_directory(options.out);
  } catch (const InputError& e) {
    std::cerr << "stepwise run: " << e.what() << '\n';
    return 2;
  } catch (const BadMethod& e) {
    std::cerr << "stepwise run: --method: " << e.what() << '\n';
    return 2;
  } catch (const std::runtime_error& e) {
    std::cerr << "stepwise run: --out: " << e.what() << '\n';
    return 2;
  }

  Measured m = run_and_measure(*p.model, p.method, p.control, p.t_end, p.output_dt);
  const std::filesystem::path out(options.out);
  try {
    write_file_atomic(out / "trajectory.csv", trajectory_csv(*p.model, m));
    write_file_atomic(out / "summary.json", summary_json(p, m).dump(2) + "\n");
  } catch (const std::runtime_error& e) {
    std::cerr << "stepwise run: " << e.what() << '\n';
    return 2;
  }
  if (m.result.status != Status::ok) {
    std::cerr << "stepwise run: " << p.method << ": " << m.result.message << '\n';
    return 1;
  }
  return 0;
}

}  // namespace stepwise
