// A user's scene file as a scene of the studies (`stepwise study NAME --scene FILE`, `stepwise advise`): its model
// made by prepare_run from the file and --set, as `stepwise run` makes it, and the time scale the sweeps start
// from read off its Jacobian's spectrum at the start.
#pragma once

#include <stepwise/report/studies/study_scenes.hpp>
#include <stepwise/run/prepare.hpp>

namespace stepwise {

// the scene, checked as `stepwise run` checks it (InputError naming the file, line or option); `prepared`, where
// given, receives the prepared run
StudyScene user_study_scene(const RunOptions& options, PreparedRun* prepared = nullptr);

// the fastest time scale of a system at its start: 1 / max |lambda| of its Jacobian, as t_end / 2^k (so that a
// sweep's steps divide t_end); t_end / 16 for a spectrum of zeros
double spectrum_time_scale(const Model& model, double t_end);

}  // namespace stepwise
