// `stepwise run`'s outputs: trajectory.csv (t, the state's names or the model's summary of a large state,
// energy where the model has one) and summary.json (docs/summary.schema.json's fields).
//
// The trajectory's rows are streamed to a temporary file as the run produces them (a long run's output is
// never held in memory). summary.json is the manifest: it is removed before the new trajectory is renamed into
// place and written last, so a reader never sees a new trajectory.csv beside an old summary.json; a
// trajectory.csv without a summary.json beside it is from a run that did not finish.
#pragma once

#include <stepwise/run/atomic_write.hpp>
#include <stepwise/run/csv.hpp>
#include <stepwise/run/measure.hpp>
#include <stepwise/run/prepare.hpp>

#include <nlohmann/json_fwd.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace stepwise {

struct DistanceConstraints;
struct Method;

// a method's own options as `stepwise methods --json` and Python's methods() list them (solvers/method.hpp's
// MethodOption): name, type, range, default, unit, help, and the key summary.json echoes it under
nlohmann::json method_options_json(const Method& method);

// the trajectory's columns and rows: trajectory.csv's, and the Python module's run() (python/module.cpp) holds the
// same numbers
class TrajectoryRows {
 public:
  explicit TrajectoryRows(const Model& model);
  // "t", the state's names or the model's summary names, and "energy" where the model has one
  const std::vector<std::string>& columns() const { return columns_; }
  // a sample's row: the state itself (energy computed from it), or already the model's summary of it; `problem`
  // receives why the run ends there (a value not finite), else stays empty
  std::vector<Cell> row(double t, const Eigen::VectorXd& sample, std::string& problem) const;
  // the row a run that stopped between output times ends with (after the last output at `last_t`), if any
  std::optional<std::vector<Cell>> stop_row(const Measured& m, double last_t) const;
  // for a model whose particles are held by distance constraints, the largest |C(x)| / length over the rows made
  // so far (solvers/capabilities/distance_constraints.hpp); else empty
  std::optional<double> constraint_drift() const;

 private:
  const Model& model_;
  std::vector<std::string> columns_;
  bool with_energy_ = false;
  const DistanceConstraints* constraints_ = nullptr;  // the model's, where its rows are its state
  mutable double drift_ = 0;
};

// summary.json (docs/summary.schema.json's fields) for a finished run, as a value and as its text; `constraint_drift` where the
// scene has constraints
nlohmann::json summary_json(const PreparedRun& p, const Measured& m, std::optional<double> constraint_drift = std::nullopt);
std::string summary_text(const PreparedRun& p, const Measured& m, std::optional<double> constraint_drift = std::nullopt);

class RunOutputs {
 public:
  // the trajectory's temporary file opened in `out`, its header and first row written (for a PDE, its fields' files
  // too: field_NAME.csv, a row per output time of t and the field at every node, row-major; grid.csv, each node's
  // x and y, written at the end); std::runtime_error naming the file when it cannot be
  RunOutputs(const std::filesystem::path& out, const PreparedRun& p);
  // whether the sink takes the whole state (a PDE's fields are written whole), not the model's summary of it: the
  // step control's observe is then the identity
  bool whole_states() const { return !fields_.empty(); }
  // a step control's sink: one row; non-empty (the run ends diverged) when a value in it is not finite
  std::string sample(double t, const Eigen::VectorXd& sample);
  // the last row of a run that stopped early, then the trajectory and the summary put in place
  void finish(const Measured& m);

 private:
  std::filesystem::path out_;
  const PreparedRun& p_;
  AtomicFile trajectory_;
  TrajectoryRows rows_;
  std::vector<std::unique_ptr<AtomicFile>> fields_;  // a PDE's field_NAME.csv, one a field
  double last_t_ = 0;  // the last row's time
};

}  // namespace stepwise
