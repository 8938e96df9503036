#include "report.hpp"

#include "run/atomic_write.hpp"
#include "pictures.hpp"
#include "run/process.hpp"
#include "studies.hpp"
#include "solvers/method_table.hpp"

#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <thread>

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

// run one study, write its CSVs into dir, add its figures to the list; return its Markdown section
std::string run_study(const Study& study, const StudyContext& ctx, const fs::path& dir, std::vector<Figure>& figures) {
  const auto start = std::chrono::steady_clock::now();
  ctx.progress->begin_study(fmt::format("{}{}", study.name, ctx.quick ? " (quick)" : ""));
  StudyOutput output = study.run(ctx);
  std::string md = fmt::format("## {}\n\n{}", study.title, output.markdown);
  md += "Data: ";
  for (const auto& [stem, table] : output.tables) {
    write_file_atomic(dir / (stem + ".csv"), to_csv(table));
    md += fmt::format("[{0}.csv]({0}.csv) ", stem);
  }
  figures.insert(figures.end(), output.figures.begin(), output.figures.end());
  ctx.progress->end_study(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return md + "\n\n";
}

// the figures' list for plot.py (figures.csv), then plot.py drawing them, and with `html` report.md as index.html
void draw_figures(const std::vector<Figure>& figures, const fs::path& dir, bool html) {
  Table list{{"stem", "kind", "subject"}, {}};
  for (const auto& f : figures) list.rows.push_back({f.stem(), f.kind, f.subject});
  write_file_atomic(dir / "figures.csv", to_csv(list));
  Table method_table{{"name", "order", "source", "kind"}, {}};
  for (const auto& m : methods()) method_table.rows.push_back({std::string(m.name), std::string(m.order.text), std::string(m.source), std::string(m.description)});
  write_file_atomic(dir / "methods.csv", to_csv(method_table));
  const std::string python = STEPWISE_PYTHON, script = fs::path(STEPWISE_REPORT_DIR) / "plot.py", where = dir.string();
  std::vector<std::string> args{python, script, where};
  if (html) args.push_back("--html");
  std::string why;
  const std::optional<int> status = run_process(args, &why);
  if (!status)
    throw std::runtime_error(fmt::format("cannot start {} for the figures ({}): install python3 (Debian's, with python3-matplotlib)", python, why));
  if (*status != 0)
    throw std::runtime_error(fmt::format("{} {} failed (exit status {}): the figures were not drawn", python, script, *status));
}

// the threads asked for, or one per core
int threads_or_default(int requested) { return requested > 0 ? requested : static_cast<int>(std::max(1u, std::thread::hardware_concurrency())); }

}  // namespace

int study_command(const std::string& name, bool quick, int threads, const std::string& out) {
  const Study* study = find_study(name);
  if (!study) {
    std::cerr << fmt::format("stepwise study: unknown study '{}' (one of {})\n", name, study_names());
    return 2;
  }
  try {
    ensure_writable_directory(out);
  } catch (const std::runtime_error& e) {
    std::cerr << "stepwise study: " << e.what() << '\n';
    return 2;
  }
  try {
    Progress progress;
    const StudyContext ctx{quick, threads_or_default(threads), &progress};
    std::vector<Figure> figures;
    write_file_atomic(fs::path(out) / (name + ".md"), run_study(*study, ctx, out, figures));
    draw_figures(figures, out, false);
  } catch (const std::runtime_error& e) {
    std::cerr << "stepwise study: " << e.what() << '\n';
    return 1;
  }
  return 0;
}

int report_command(bool quick, int threads, const std::string& out, const std::string& scenes_dir) {
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
    // mkdtemp's 0700 widened to what a directory made the usual way gets
    fs::permissions(staging, static_cast<fs::perms>(default_mode(true)));
  } catch (const std::runtime_error& e) {
    std::cerr << "stepwise report: --out: " << e.what() << '\n';
    return 2;
  }

  const auto start = std::chrono::steady_clock::now();
  Progress progress;
  const StudyContext ctx{quick, threads_or_default(threads), &progress};
  std::string md = fmt::format("# stepwise report{}\n\n", quick ? " (quick)" : "");
  md += "Every table and figure below is computed by this run from the CSV files named under it, in this directory.\n\n";
  std::vector<Figure> figures;
  std::error_code ec;
  try {
    for (const auto& study : studies()) md += run_study(study, ctx, staging, figures);
    md += pictures_section(staging, scenes_dir, ctx);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    md += fmt::format("---\nStudies run in {:.1f} s of wall time on {} threads.\n", seconds, ctx.threads);
    write_file_atomic(staging / "report.md", md);
    draw_figures(figures, staging, true);
  } catch (const std::exception& e) {
    fs::remove_all(staging, ec);
    std::cerr << "stepwise report: " << e.what() << '\n';
    return 1;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // swap: the old report is moved aside, the new one renamed into place, then the old one removed
  const fs::path old = parent / fmt::format(".{}.old", target.filename().string());
  fs::remove_all(old, ec);
  if (fs::exists(target)) fs::rename(target, old);
  fs::rename(staging, target);
  fs::remove_all(old, ec);
  std::cerr << fmt::format("stepwise: report written to {} in {:.1f} s\n", target.string(), seconds);
  return 0;
}

}  // namespace stepwise
