// The report's "Side by side": the flag, the 170-degree pendulum and the water drop, each run by three methods at
// one CPU budget and filmed beside the converged reference (run/side_by_side.hpp), so that what the numbers say
// of a cheap method can be seen.
#pragma once

#include <stepwise/report/studies.hpp>

#include <filesystem>
#include <string>

namespace stepwise {

// the side-by-side study, a drawn one: the clips of the context's scenes_dir filmed into its out/side_by_side/CLIP.mp4
// (the clips run as the context's sweep), with side_by_side.csv and side_by_side_frames.csv. Without ffmpeg it films
// nothing and says so, in the section and in one line on stderr
Study side_by_side_study();

}  // namespace stepwise
