// Studies (sweeps written as CSV/JSON) and the report built from them (`stepwise study`, `stepwise report`).
#pragma once

#include <string>

namespace stepwise {

// the study names, " | " between them
std::string study_names();

// run one study into out/ (CSV, Markdown, its figures); its points on `threads` threads (0: one per core).
// Exit status 0, 1 when a study or its figures failed, 2 for an unknown name or unwritable out
int study_command(const std::string& name, bool quick, int threads, const std::string& out);

// every study, then out/report.md, the figures and out/index.html; written to a temporary directory and moved
// into place at the end, so a failed or interrupted run leaves the previous report as it was
int report_command(bool quick, int threads, const std::string& out, const std::string& scenes_dir);

}  // namespace stepwise
