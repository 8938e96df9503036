// The report's "Side by side": the flag, the 170-degree pendulum and the water drop, each run by three methods at
// one CPU budget and filmed beside the converged reference (run/side_by_side.hpp), so that what the numbers say
// of a cheap method can be seen.
#pragma once

#include <stepwise/report/sweep.hpp>

#include <filesystem>
#include <string>

namespace stepwise {

// films the scenes of scenes_dir into dir/side_by_side/SCENE.mp4 (the clips run as the context's sweep), writes
// dir/side_by_side.csv and dir/side_by_side_frames.csv, and returns the report's section. Without ffmpeg it
// films nothing and says so, in the section and in one line on stderr
std::string side_by_side_section(const std::filesystem::path& dir, const std::filesystem::path& scenes_dir, const StudyContext& ctx);

}  // namespace stepwise
