// Studies (sweeps written as CSV/JSON) and the report built from them (`stepwise study`, `stepwise report`).
#pragma once

#include <stepwise/run/prepare.hpp>

#include <filesystem>
#include <optional>
#include <utility>
#include <vector>
#include <string>
#include <string_view>

#include <string>

namespace stepwise {

// the study names, " | " between them
std::string study_names();
// every study `stepwise study` runs: its name and what it measures
std::vector<std::pair<std::string, std::string>> study_list();

// run one study into out/ (CSV, Markdown, its figures); its points on `threads` threads (0: one per core).
// Exit status 0, 1 when a study or its figures failed, 2 for an unknown name or unwritable out
// `scene`: the user's scene file (--scene, with its --set) in place of the study's own scenes, for the studies
// that take one (scene_studies()); exit status 2 for another
int study_command(const std::string& name, bool quick, int threads, const std::string& out, const std::optional<RunOptions>& scene = std::nullopt);

// plot.py's figures (kind and subject: report/studies.hpp's Figure) drawn into dir from its CSVs, by `jobs`
// processes; with `html`, report.md as index.html too
struct Figure;
void draw_figures(const std::vector<Figure>& figures, const std::filesystem::path& dir, int jobs, bool html);

// the threads asked for, or one per core
int threads_or_default(int requested);

// the studies that take --scene (report/studies.hpp's Study::scene_problem), ", " between them
std::string scene_studies();

// the study of that name, or null
struct Study;
const Study* find_study(const std::string& name);

// the user's scene for study `name` (`stepwise study NAME --scene FILE`, Python's stepwise.study): checked as
// `stepwise run` checks it; InputError, the command's message, for a study that runs on its own scenes or an
// energy study on a scene with no energy formula
struct StudyScene;
StudyScene study_scene_of(const std::string& name, const RunOptions& scene);

// every study, then out/report.md, the figures and out/index.html; written to a temporary directory and moved
// into place at the end, so a failed or interrupted run leaves the previous report as it was
int report_command(bool quick, int threads, const std::string& out, const std::string& scenes_dir);

}  // namespace stepwise
