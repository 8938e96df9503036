#include "run_outputs.hpp"

#include "run/csv.hpp"
#include "models/equations.hpp"
#include "models/pde.hpp"
#include "solvers/capabilities/distance_constraints.hpp"
#include "solvers/method_table.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>

namespace stepwise {

nlohmann::json method_options_json(const Method& method) {
  using Kind = MethodOption::Kind;
  nlohmann::json options = nlohmann::json::array();
  for (const auto& o : method.options) {
    nlohmann::json j{{"name", o.name}, {"type", o.kind == Kind::whole ? "whole" : o.kind == Kind::real ? "real" : "choice"}, {"unit", o.unit},
                     {"help", o.help}, {"summary_key", o.key()}};
    if (o.kind == Kind::choice) {
      j["choices"] = o.choices;
      j["default"] = o.value_text(o.fallback);
    } else {
      j[o.kind == Kind::whole ? "minimum" : "exclusive_minimum"] = o.min;
      j[o.kind == Kind::whole ? "maximum" : "exclusive_maximum"] = o.max;
      j["default"] = o.fallback;
    }
    options.push_back(std::move(j));
  }
  return options;
}
namespace {

// columns: the state's names, or the model's summary of a large state; energy beside them where it exists
std::vector<std::string> sample_names(const Model& model) {
  auto names = model.summary_names();
  return names.empty() ? model.state_names() : names;
}

}  // namespace

nlohmann::json summary_json(const PreparedRun& p, const Measured& m, std::optional<double> constraint_drift) {
  const RunResult& r = m.result;
  nlohmann::json j;
  j["scene"] = p.scene.name;
  j["scene_file"] = p.scene.file;
  j["model"] = std::string(p.model->name());
  j["method"] = p.method;
  j["status"] = std::string(to_string(r.status));
  j["message"] = r.message.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.message);
  j["t_end"] = p.t_end;
  j["t_stop"] = r.status == Status::ok && !r.terminated ? p.t_end : r.t_stop;
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
  if (r.stats.newton_iterations > 0) {
    // a Newton on the incremental potential: its iterations and line-search halvings, in all and a step
    const double steps = static_cast<double>(std::max(1L, r.stats.steps));
    j["newton_iterations"] = r.stats.newton_iterations;
    j["line_search_halvings"] = r.stats.line_search_halvings;
    j["newton_iterations_per_step"] = static_cast<double>(r.stats.newton_iterations) / steps;
    j["line_search_halvings_per_step"] = static_cast<double>(r.stats.line_search_halvings) / steps;
  }
  if (r.stats.colours > 0) {
    // a per-vertex solver (vbd): its colours, and how far its sweeps lowered the incremental potential, in all and a step
    j["colours"] = r.stats.colours;
    j["potential_decrease"] = r.stats.potential_decrease;
    j["potential_decrease_per_step"] = r.stats.potential_decrease / static_cast<double>(std::max(1L, r.stats.steps));
  }
  j["cpu_seconds"] = r.stats.cpu_seconds;
  j["ranks"] = p.ranks;
  const auto names = sample_names(*p.model);
  const Eigen::VectorXd final_sample = p.model->summary(r.y_stop);
  j["final_state"] = nlohmann::json::object();
  for (size_t i = 0; i < names.size(); ++i) j["final_state"][names[i]] = final_sample[static_cast<Eigen::Index>(i)];
  j["error"] = m.error ? nlohmann::json(*m.error) : nlohmann::json(nullptr);
  // a PDE against its [exact]: the max error over the grid, and each field's max and root-mean-square error
  if (const PdeGrid* grid = pde_grid(*p.model); grid && grid->exact && r.status == Status::ok && r.y_stop.allFinite()) {
    const Eigen::VectorXd error = r.y_stop - grid->exact(r.t_stop);
    j["error"] = error.cwiseAbs().maxCoeff();
    for (size_t f = 0; f < grid->fields.size(); ++f) {
      const auto e = error.segment(static_cast<Eigen::Index>(f) * grid->nodes(), grid->nodes());
      j["error_max"][grid->fields[f]] = e.cwiseAbs().maxCoeff();
      j["error_l2"][grid->fields[f]] = std::sqrt(e.squaredNorm() / grid->nodes());
    }
  }
  if (const auto e0 = p.model->energy(p.model->initial_state())) {
    j["energy_initial"] = *e0;
    j["energy_final"] = *p.model->energy(r.y_stop);
  }
  j["events"] = nlohmann::json::array();
  const auto events = events_of(*p.model);
  const auto state_names = p.model->state_names();
  const auto state = [&](const Eigen::VectorXd& y) {
    nlohmann::json s = nlohmann::json::object();
    for (size_t i = 0; i < state_names.size() && i < static_cast<size_t>(y.size()); ++i) s[state_names[i]] = y[static_cast<Eigen::Index>(i)];
    return s;
  };
  for (const auto& e : r.events) {
    nlohmann::json event = {{"t", e.t}, {"kind", e.kind}, {"event", e.event < events.size() ? events[e.event].name : "contacts"}};
    // a scene's own events: the state where it was found, and after its action
    if (e.before.size() > 0) {
      event["state"] = state(e.before);
      event["state_after"] = state(e.after);
    }
    j["events"].push_back(std::move(event));
  }
  if (r.terminated && !r.events.empty()) j["terminal_event"] = events[r.events.back().event].name;
  j["parameters"] = nlohmann::json::object();
  for (const auto& [key, value] : p.params) j["parameters"][key] = value;
  if (!p.method_choice.empty()) j["method_choice"] = p.method_choice;
  if (constraint_drift) j["constraint_drift"] = *constraint_drift;
  if (!p.constraint.empty()) j["constraint"] = p.constraint;
  // the method's own options, each as the run used it (given or its default), under its key
  if (const Method* method = find_method(p.method))
    for (const auto& o : method->options) {
      const double value = method->setting(p.control, o.name);
      if (o.kind == MethodOption::Kind::choice) j[std::string(o.key())] = o.value_text(value);
      else if (o.kind == MethodOption::Kind::whole) j[std::string(o.key())] = static_cast<long long>(value);
      else j[std::string(o.key())] = value;
    }
  // a scene's own equations: whether the compiled right-hand side ran or the interpreter, and why
  if (const auto e = equations_evaluation(*p.model)) {
    // a compile still running in the background when the run ended is stopped with the model
    const std::string detail = e->background && !e->compiled && e->compile_seconds == 0 ? e->detail + "; the run ended first, and the compile was stopped" : e->detail;
    j["equations"] = {{"evaluation", e->compiled ? "compiled" : "interpreted"}, {"detail", detail}, {"second_order", e->second_order > 0},
                      {"c_bytes", e->source_bytes}, {"compile_units", e->units}, {"compiled_in_background", e->background}};
    if (!e->exact_note.empty()) j["equations"]["exact"] = e->exact_note;
  }
  return j;
}

TrajectoryRows::TrajectoryRows(const Model& model) : model_(model), columns_{"t"} {
  for (const auto& name : sample_names(model)) columns_.push_back(name);
  with_energy_ = model.summary_names().empty() && model.energy(model.initial_state()).has_value();
  if (with_energy_) columns_.emplace_back("energy");
  if (model.summary_names().empty()) constraints_ = model.as<DistanceConstraints>();
}

std::vector<Cell> TrajectoryRows::row(double t, const Eigen::VectorXd& sample, std::string& problem) const {
  std::vector<Cell> row{t};
  row.reserve(static_cast<size_t>(sample.size()) + 2);
  for (const double v : sample) row.emplace_back(v);
  if (with_energy_) row.emplace_back(*model_.energy(sample));
  if (constraints_) drift_ = std::max(drift_, constraints_->drift(sample.data()));
  for (size_t i = 1; i < row.size() && problem.empty(); ++i)
    if (!std::isfinite(std::get<double>(row[i])))
      problem = fmt::format("{} overflowed ({})", i == static_cast<size_t>(sample.size()) + 1 ? std::string("the energy") : "a sampled value",
                            std::get<double>(row[i]));
  return row;
}

std::optional<std::vector<Cell>> TrajectoryRows::stop_row(const Measured& m, double last_t) const {
  if (m.result.status == Status::ok || m.result.t_stop <= last_t || !m.result.y_stop.allFinite()) return std::nullopt;
  std::string ignored;
  return row(m.result.t_stop, model_.summary(m.result.y_stop), ignored);
}

std::optional<double> TrajectoryRows::constraint_drift() const {
  if (!constraints_) return std::nullopt;
  return drift_;
}

std::string summary_text(const PreparedRun& p, const Measured& m, std::optional<double> constraint_drift) {
  return summary_json(p, m, constraint_drift).dump(2) + "\n";
}

RunOutputs::RunOutputs(const std::filesystem::path& out, const PreparedRun& p) : out_(out), p_(p), trajectory_(out / "trajectory.csv"), rows_(*p.model) {
  std::vector<Cell> header;
  for (const auto& name : rows_.columns()) header.emplace_back(name);
  trajectory_.write(csv_row(header));
  if (const PdeGrid* grid = pde_grid(*p.model)) {
    std::vector<Cell> nodes{std::string("t")};
    for (int n = 0; n < grid->nodes(); ++n) nodes.emplace_back(fmt::format("node{}", n));
    for (const auto& field : grid->fields) {
      fields_.push_back(std::make_unique<AtomicFile>(out / fmt::format("field_{}.csv", field)));
      fields_.back()->write(csv_row(nodes));
    }
  }
  const Eigen::VectorXd y0 = p.model->initial_state();
  sample(0.0, whole_states() ? y0 : p.model->summary(y0));
}

std::string RunOutputs::sample(double t, const Eigen::VectorXd& sample) {
  std::string problem;
  if (whole_states()) {
    const auto nodes = static_cast<Eigen::Index>(sample.size() / static_cast<Eigen::Index>(fields_.size()));
    for (size_t f = 0; f < fields_.size(); ++f) {
      std::vector<Cell> row{t};
      for (const double value : sample.segment(static_cast<Eigen::Index>(f) * nodes, nodes)) row.emplace_back(value);
      fields_[f]->write(csv_row(row));
    }
    trajectory_.write(csv_row(rows_.row(t, p_.model->summary(sample), problem)));
  } else {
    trajectory_.write(csv_row(rows_.row(t, sample, problem)));
  }
  last_t_ = t;
  return problem;
}

void RunOutputs::finish(const Measured& m) {
  // the states before and after the events after the last output (a terminal event's)
  for (size_t k = m.result.events_written; k < m.result.events.size(); ++k)
    if (const EventRecord& e = m.result.events[k]; opens_instant(m.result.events, k))
      for (const Eigen::VectorXd* state : {&e.before, &e.after}) (void)sample(e.t, p_.model->summary(*state));
  // a run that stopped between output times ends its trajectory where it stopped
  if (const auto last = rows_.stop_row(m, last_t_)) trajectory_.write(csv_row(*last));
  std::error_code ignored;
  std::filesystem::remove(out_ / "summary.json", ignored);  // the manifest goes first and comes back last
  trajectory_.commit();
  for (const auto& field : fields_) field->commit();
  if (const PdeGrid* grid = pde_grid(*p_.model)) {
    std::string nodes = csv_row({std::string("x"), std::string("y")});
    for (int n = 0; n < grid->nodes(); ++n) nodes += csv_row({grid->x[static_cast<size_t>(n)], grid->y[static_cast<size_t>(n)]});
    write_file_atomic(out_ / "grid.csv", nodes);
  }
  std::optional<double> drift = rows_.constraint_drift();
  if (const auto* c = p_.model->as<DistanceConstraints>(); drift && m.result.y_stop.allFinite()) drift = std::max(*drift, c->drift(m.result.y_stop.data()));
  write_file_atomic(out_ / "summary.json", summary_text(p_, m, drift));
}

}  // namespace stepwise
