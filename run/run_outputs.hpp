// `stepwise run`'s outputs: trajectory.csv (t, the state's names or the model's summary of a large state,
// energy where the model has one) and summary.json (DESIGN.md's fields), each written whole and renamed.
#pragma once

#include "run/measure.hpp"
#include "run/prepare.hpp"

#include <filesystem>

namespace stepwise {

// std::runtime_error naming the file that could not be written
void write_run_outputs(const std::filesystem::path& out, const PreparedRun& p, const Measured& m);

}  // namespace stepwise
