#include "run_outputs.hpp"

#include "run/atomic_write.hpp"
#include "run/csv.hpp"

#include <nlohmann/json.hpp>

namespace stepwise {
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

void write_run_outputs(const std::filesystem::path& out, const PreparedRun& p, const Measured& m) {
  write_file_atomic(out / "trajectory.csv", trajectory_csv(*p.model, m));
  write_file_atomic(out / "summary.json", summary_json(p, m).dump(2) + "\n");
}

}  // namespace stepwise
