// `stepwise run`: a scene through one method, written as trajectory.csv and summary.json.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace stepwise {

struct RunOptions {
  std::string scene_file;
  std::vector<std::string> sets;  // "key=value" overrides of scene parameters
  std::optional<std::string> method;
  std::optional<std::string> event_location;  // linear | restep
  std::optional<double> dt, rtol, atol, t_end, output_dt;
  std::string out;
};

// exit status: 0 ok, 1 diverged or failed (summary written), 2 bad input (nothing written)
int run_command(const RunOptions& options);

}  // namespace stepwise
