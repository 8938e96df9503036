#include "run_outputs.hpp"

#include "run/csv.hpp"
#include "models/equations.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>

namespace stepwise {
namespace {

// columns: the state's names, or the model's summary of a large state; energy beside them where it exists
std::vector<std::string> sample_names(const Model& model) {
  auto names = model.summary_names();
  return names.empty() ? model.state_names() : names;
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
  j["ranks"] = p.ranks;
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
  // a scene's own equations: whether the compiled right-hand side ran or the interpreter, and why
  if (const auto e = equations_evaluation(*p.model)) {
    j["equations"] = {{"evaluation", e->compiled ? "compiled" : "interpreted"}, {"detail", e->detail}, {"second_order", e->second_order > 0}};
    if (!e->exact_note.empty()) j["equations"]["exact"] = e->exact_note;
  }
  return j;
}

}  // namespace

RunOutputs::RunOutputs(const std::filesystem::path& out, const PreparedRun& p) : out_(out), p_(p), trajectory_(out / "trajectory.csv") {
  const Model& model = *p.model;
  std::vector<Cell> header{std::string("t")};
  for (const auto& name : sample_names(model)) header.emplace_back(name);
  with_energy_ = model.summary_names().empty() && model.energy(model.initial_state()).has_value();
  if (with_energy_) header.emplace_back(std::string("energy"));
  trajectory_.write(csv_row(header));
  sample(0.0, model.summary(model.initial_state()));
}

// a sample is the state itself (energy computed from it), or already the model's summary of it
std::string RunOutputs::sample(double t, const Eigen::VectorXd& sample) {
  std::vector<Cell> row{t};
  row.reserve(static_cast<size_t>(sample.size()) + 2);
  for (const double v : sample) row.emplace_back(v);
  if (with_energy_) row.emplace_back(*p_.model->energy(sample));
  trajectory_.write(csv_row(row));
  last_t_ = t;
  for (size_t i = 1; i < row.size(); ++i)
    if (!std::isfinite(std::get<double>(row[i])))
      return fmt::format("{} overflowed ({})", i == static_cast<size_t>(sample.size()) + 1 ? std::string("the energy") : "a sampled value",
                         std::get<double>(row[i]));
  return {};
}

void RunOutputs::finish(const Measured& m) {
  // a run that stopped between output times ends its trajectory where it stopped
  if (m.result.status != Status::ok && m.result.t_stop > last_t_ && m.result.y_stop.allFinite()) {
    const Eigen::VectorXd last = p_.model->summary(m.result.y_stop);
    std::vector<Cell> row{m.result.t_stop};
    for (const double v : last) row.emplace_back(v);
    if (with_energy_) row.emplace_back(*p_.model->energy(last));
    trajectory_.write(csv_row(row));
  }
  std::error_code ignored;
  std::filesystem::remove(out_ / "summary.json", ignored);  // the manifest goes first and comes back last
  trajectory_.commit();
  write_file_atomic(out_ / "summary.json", summary_json(p_, m).dump(2) + "\n");
}

}  // namespace stepwise
