// `stepwise run`'s outputs: trajectory.csv (t, the state's names or the model's summary of a large state,
// energy where the model has one) and summary.json (DESIGN.md's fields).
//
// The trajectory's rows are streamed to a temporary file as the run produces them (a long run's output is
// never held in memory). summary.json is the manifest: it is removed before the new trajectory is renamed into
// place and written last, so a reader never sees a new trajectory.csv beside an old summary.json; a
// trajectory.csv without a summary.json beside it is from a run that did not finish.
#pragma once

#include "run/atomic_write.hpp"
#include "run/measure.hpp"
#include "run/prepare.hpp"

#include <filesystem>

namespace stepwise {

class RunOutputs {
 public:
  // the trajectory's temporary file opened in `out`, its header and first row written; std::runtime_error
  // naming the file when it cannot be
  RunOutputs(const std::filesystem::path& out, const PreparedRun& p);
  // a step control's sink: one row; non-empty (the run ends diverged) when a value in it is not finite
  std::string sample(double t, const Eigen::VectorXd& sample);
  // the last row of a run that stopped early, then the trajectory and the summary put in place
  void finish(const Measured& m);

 private:
  std::filesystem::path out_;
  const PreparedRun& p_;
  AtomicFile trajectory_;
  bool with_energy_ = false;
  double last_t_ = 0;  // the last row's time
};

}  // namespace stepwise
