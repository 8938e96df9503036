// `stepwise run`: a scene through one method, written as trajectory.csv and summary.json.
#pragma once

#include "run/prepare.hpp"


namespace stepwise {

// exit status: 0 ok, 1 diverged or failed (summary written), 2 bad input (nothing written)
int run_command(const RunOptions& options);

}  // namespace stepwise
