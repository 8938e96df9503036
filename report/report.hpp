// Studies (sweeps written as CSV/JSON) and the report built from them (`stepwise study`, `stepwise report`).
#pragma once

#include <string>

namespace stepwise {

// "convergence | work-precision | energy | adequacy"
std::string study_names();

// run one study into out/ (CSV + Markdown); exit status 0, or 2 for an unknown name or unwritable out
int study_command(const std::string& name, bool quick, const std::string& out);

// every study, then out/report.md; written to a temporary directory and moved into place at the end
int report_command(bool quick, const std::string& out);

}  // namespace stepwise
