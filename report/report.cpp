#include "report.hpp"

#include "atomic_write.hpp"
#include "studies.hpp"

#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <iostream>

namespace stepwise {
namespace fs = std::filesystem;

std::string study_names() {
  std::string names;
  for (const auto& s : studies()) names += (names.empty() ? "" : " | ") + std::string(s.name);
  return names;
}

namespace {

const Study* find_study(const std::string& name) {
  for (const auto& s : studies())
    if (s.name == name) return &s;
  return nullptr;
}

// run one study, write its CSVs into dir, return its Markdown section
std::string run_study(const Study& study, bool quick, const fs::path& dir) {
  const auto start = std::chrono::steady_clock::now();
  std::cerr << "stepwise: study " << study.name << (quick ? " (quick)" : "") << " ..." << std::flush;
  StudyOutput output = study.run(quick);
  std::string md = fmt::format("## {}\n\n{}", study.title, output.markdown);
  md += "Data: ";
  for (const auto& [stem, table] : output.tables) {
    write_file_atomic(dir / (stem + ".csv"), to_csv(table));
    md += fmt::format("[{0}.csv]({0}.csv) ", stem);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cerr << fmt::format(" {:.1f} s\n", seconds);
  return md + "\n\n";
}

}  // namespace

int study_command(const std::string& name, bool quick, const std::string& out) {
  const Study* study = find_study(name);
  if (!study) {
    std::cerr << fmt::format("stepwise study: unknown study '{}' (one of {})\n", name, study_names());
    return 2;
  }
  try {
    ensure_writable_directory(out);
    write_file_atomic(fs::path(out) / (name + ".md"), run_study(*study, quick, out));
  } catch (const std::runtime_error& e) {
    std::cerr << "stepwise study: " << e.what() << '\n';
    return 2;
  }
  return 0;
}

int report_command(bool quick, const std::string& out) {
  const fs::path target = fs::absolute(out).lexically_normal();
  const fs::path parent = target.parent_path();
  fs::path staging;
  try {
    // the old report is replaced whole: never a directory that is something else (a source folder, a home)
    if (fs::exists(target) && !(fs::is_directory(target) && (fs::is_empty(target) || fs::exists(target / "report.md"))))
      throw std::runtime_error(fmt::format("{}: exists and is not a stepwise report (no report.md); refusing to replace it",
                                           target.string()));
    ensure_writable_directory(parent);
    // the report is built beside its target and swapped in whole at the end
    std::string pattern = (parent / fmt::format(".{}.tmp-XXXXXX", target.filename().string())).string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error(fmt::format("{}: cannot create a staging directory", parent.string()));
    staging = pattern;
  } catch (const std::runtime_error& e) {
    std::cerr << "stepwise report: --out: " << e.what() << '\n';
    return 2;
  }

  const auto start = std::chrono::steady_clock::now();
  std::string md = fmt::format("# stepwise report{}\n\n", quick ? " (quick)" : "");
  md += "Every table below is computed by this run from the CSV file named under it.\n\n";
  for (const auto& study : studies()) md += run_study(study, quick, staging);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  md += fmt::format("---\nGenerated in {:.1f} s of wall time.\n", seconds);
  write_file_atomic(staging / "report.md", md);

  // swap: the old report is moved aside, the new one renamed into place, then the old one removed
  const fs::path old = parent / fmt::format(".{}.old", target.filename().string());
  std::error_code ec;
  fs::remove_all(old, ec);
  if (fs::exists(target)) fs::rename(target, old);
  fs::rename(staging, target);
  fs::remove_all(old, ec);
  std::cerr << fmt::format("stepwise: report written to {} in {:.1f} s\n", target.string(), seconds);
  return 0;
}

}  // namespace stepwise
