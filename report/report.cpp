#include "report.hpp"
#include "report/user_scene.hpp"

#include "report/cost_model.hpp"
#include "run/atomic_write.hpp"
#include "run/process.hpp"
#include "run/message.hpp"
#include "run/prepare.hpp"
#include "run/interrupt.hpp"
#include "run/provenance.hpp"
#include "run/ranks.hpp"
#include "run/scene.hpp"
#include "studies.hpp"
#include "solvers/method_table.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <memory>
#include <filesystem>
#include <iostream>
#include <thread>

namespace stepwise {
namespace fs = std::filesystem;

std::vector<std::pair<std::string, std::string>> study_list() {
  std::vector<std::pair<std::string, std::string>> list;
  for (const auto& s : studies()) list.emplace_back(s.name, s.title);
  return list;
}

std::string study_names() {
  std::string names;
  for (const auto& [name, title] : study_list()) names += (names.empty() ? "" : " | ") + name;
  return names;
}

namespace {

// the bytes a report takes (its folder's size: docs/performance.md) with a margin:
// checked free before any work starts
double report_bytes(bool quick) { return quick ? 28e6 : 60e6; }

}  // namespace

namespace {

constexpr const char* report_marker = ".stepwise-report.json";


// run one study, write its CSVs into dir (rank 0: the others compute their share and write nothing), add its
// figures to the list and its findings (each linking to the section, anchored by the study's name) to
// `findings` where given; return its Markdown section
std::string run_study(const Study& study, const StudyContext& ctx, const fs::path& dir, std::vector<Figure>& figures,
                      std::vector<std::string>* findings) {
  const auto start = std::chrono::steady_clock::now();
  if (ctx.progress) ctx.progress->begin_study(fmt::format("{}{}", study.name, ctx.quick ? " (quick)" : ""));
  StudyOutput output = study.run(ctx);
  std::string md = fmt::format("<a id=\"{}\"></a>\n\n## {}\n\n{}", study.name, study.title, output.markdown);
  if (findings)
    for (const auto& f : output.findings) findings->push_back(fmt::format("- {} ([the evidence](#{}))", f, study.name));
  md += "Data: ";
  for (const auto& [stem, table] : output.tables) {
    if (ranks::rank() == 0) write_file_atomic(dir / (stem + ".csv"), to_csv(table));
    md += fmt::format("[{0}.csv]({0}.csv) ", stem);
  }
  figures.insert(figures.end(), output.figures.begin(), output.figures.end());
  if (ctx.progress) ctx.progress->end_study(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return md + "\n\n";
}

// provenance.json into dir: what ran, where, when, and how the ranks shared the sweeps
void write_provenance(const fs::path& dir, std::string command, const StudyContext& ctx, std::chrono::system_clock::time_point start) {
  write_file_atomic(dir / "provenance.json",
                    provenance_json({std::move(command), ctx.threads, start, std::chrono::system_clock::now(), ctx.load ? ctx.load->seconds : std::vector<double>{},
                                     ctx.progress ? ctx.progress->slowness() : 0}));
}

// Under mpirun every rank runs the command and the sweeps' points are shared among them (report/sweep.hpp);
// rank 0 alone checks the output directory and writes. A failure every rank sees alike (a point that failed:
// SweepError; a check of rank 0's that every rank is told of) ends each rank normally; one only this rank
// sees would leave the others waiting for it at the next sweep, so it stops them all (MPI_Abort), after rank 0
// has put its outputs back as they were. `together`: the sweeps are not over (after them rank 0 writes alone).
int fail(const char* command, const std::exception& e, bool together) {
  const bool shared = dynamic_cast<const SweepError*>(&e) != nullptr;
  if (ranks::rank() == 0) print_error(command, e.what());
  else if (!shared) print_error(command, fmt::format("rank {}: {}", ranks::rank(), e.what()));
  if (ranks::size() > 1 && together && !shared) ranks::abort_all(1);
  return 1;
}

}  // namespace

// the figures' list for plot.py (figures.csv), then plot.py drawing them by `jobs` processes, and with `html`
// report.md as index.html
void draw_figures(const std::vector<Figure>& figures, const fs::path& dir, int jobs, bool html) {
  Table list{{"stem", "kind", "subject"}, {}};
  // the figures' specs, by stem, for plot.py's and interactive.py's one drawer each
  nlohmann::json declared = nlohmann::json::object();
  for (const auto& f : figures) {
    list.rows.push_back({f.stem(), f.kind, f.subject});
    declared[f.stem()] = f.spec.json();
  }
  write_file_atomic(dir / "figures.csv", to_csv(list));
  write_file_atomic(dir / "figures.json", declared.dump(1) + "\n");
  // group: what a figure's legend gathers a method under (a colour each), from the table's typed attributes: whose
  // code steps, and ARKODE's methods by kind (IMEX: needs the model's split; DIRK: keeps Newton matrices)
  Table method_table{{"name", "order", "source", "kind", "group"}, {}};
  for (const auto& m : methods()) {
    const std::string group = m.family != Family::arkode ? std::string(to_string(m.source))
                              : m.needs.type ? "ARKODE IMEX" : m.dense != DenseMatrices::none ? "ARKODE DIRK" : "ARKODE ERK";
    method_table.rows.push_back({std::string(m.name), std::string(m.order.text), std::string(to_string(m.source)), std::string(m.description), group});
  }
  write_file_atomic(dir / "methods.csv", to_csv(method_table));
  const std::string python = STEPWISE_PYTHON, script = fs::path(STEPWISE_REPORT_DIR) / "plot.py", where = dir.string();
  std::vector<std::string> args{python, script, where, "--jobs", std::to_string(jobs)};
  if (html) args.push_back("--html");
  std::string why;
  const std::optional<int> status = run_process(args, &why);
  if (!status)
    throw std::runtime_error(fmt::format("cannot start {} for the figures ({}): install python3 (Debian's, with python3-matplotlib)", python, why));
  if (*status != 0)
    throw std::runtime_error(fmt::format("{} {} failed (exit status {}): the figures were not drawn", python, script, *status));
}

namespace {

// the report's marker: the names it wrote at the top of its directory, so that a later report replaces only those
void write_report_marker(const fs::path& dir) {
  nlohmann::json files = nlohmann::json::array();
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  for (const auto& name : names) files.push_back(name);
  write_file_atomic(dir / report_marker, nlohmann::json{{"written_by", "stepwise report"}, {"files", files}}.dump(2) + "\n");
}

// the names an earlier report's marker lists (plain names only: nothing outside its directory)
std::vector<std::string> marked_files(const fs::path& dir) {
  std::vector<std::string> names;
  std::ifstream in(dir / report_marker);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_object() && j.contains("files") && j["files"].is_array())
    for (const auto& f : j["files"])
      if (f.is_string()) {
        const std::string name = f.get<std::string>();
        if (!name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos) names.push_back(name);
      }
  return names;
}

// the new report in place of the old: the old directory moved aside and the new one renamed in (one rename,
// so a reader sees one report or the other), then what the old marker does not list (a user's own files)
// moved back in beside the new report, and only what it lists removed
void swap_report(const fs::path& staging, const fs::path& target) {
  const fs::path old = target.parent_path() / fmt::format(".{}{}old", target.filename().string(), interrupt::temporary_tag());
  const bool had_old = fs::exists(target);
  const std::vector<std::string> listed = had_old ? marked_files(target) : std::vector<std::string>{};
  const interrupt::Uninterrupted swapping;
  if (had_old) fs::rename(target, old);
  fs::rename(staging, target);
  if (!had_old) return;
  std::error_code ec;
  std::vector<std::string> kept;
  for (const auto& entry : fs::directory_iterator(old)) {
    const std::string name = entry.path().filename().string();
    if (name == report_marker || std::find(listed.begin(), listed.end(), name) != listed.end()) continue;
    if (fs::exists(target / name)) kept.push_back(name);
    else fs::rename(entry.path(), target / name, ec);
  }
  for (const auto& name : listed) fs::remove_all(old / name, ec);
  fs::remove(old / report_marker, ec);
  if (!fs::remove(old, ec) || ec)
    print_error("report", fmt::format("{}: kept, with {} file(s) of yours the new report has a file of the same name for", old.string(), kept.size()));
}

}  // namespace

const Study* find_study(const std::string& name) {
  for (const auto& s : studies())
    if (s.name == name) return &s;
  return nullptr;
}

std::string scene_studies() {
  std::string names;
  for (const auto& s : studies())
    if (s.takes_scene()) names += fmt::format("{}{}", names.empty() ? "" : ", ", s.name);
  return names;
}

StudyScene study_scene_of(const std::string& name, const RunOptions& scene) {
  const Study* study = find_study(name);
  if (!study || !study->takes_scene())
    throw InputError(fmt::format("--scene: study {} runs on its own scenes (those that take --scene: {})", name, scene_studies()));
  StudyScene s = user_study_scene(scene);
  if (const std::string problem = study->scene_problem(s, *scene_model(s)); !problem.empty())
    throw InputError(fmt::format("--scene: {} {}", scene.scene_file, problem));
  return s;
}

int threads_or_default(int requested) { return requested > 0 ? requested : static_cast<int>(std::max(1u, std::thread::hardware_concurrency())); }

int study_command(const std::string& name, bool quick, int threads, const std::string& out, const std::optional<RunOptions>& scene) {
  const bool writer = ranks::rank() == 0;
  const Study* study = find_study(name);
  if (!study) {
    if (writer) print_error("study", fmt::format("unknown study '{}' (the studies: `stepwise study --list`)", name));
    return 2;
  }
  // the user's scene, checked as `stepwise run` checks it, before anything runs
  std::vector<StudyScene> user_scenes;
  if (scene) {
    try {
      user_scenes.push_back(study_scene_of(name, *scene));
    } catch (const InputError& e) {
      if (writer) print_error("study", e.what());
      return 2;
    }
  }
  bool usable = true;
  if (writer) try {
      ensure_writable_directory(out);
      interrupt::remove_stale(out);
    } catch (const std::runtime_error& e) {
      print_error("study", e.what());
      usable = false;
    }
  if (!ranks::all_agree(usable)) return 2;
  bool together = true;
  try {
    const auto start = std::chrono::system_clock::now();
    Progress progress;
    if (writer) progress.set_slowness(machine_slowness());
    RankLoad load;
    StudyContext ctx{quick, threads_or_default(threads), writer ? &progress : nullptr};
    ctx.load = &load;
    if (scene) ctx.scenes = &user_scenes;
    ctx.out = out;
    ctx.scenes_dir = scenes_directory();
    std::vector<Figure> figures;
    if (study->drawn) {  // rank 0's alone, as in the report
      together = false;
      if (!writer) return 0;
      ctx.distribute = false;
      ctx.load = nullptr;
    }
    const std::string md = run_study(*study, ctx, out, figures, nullptr);
    together = false;
    if (!writer) return 0;
    write_file_atomic(fs::path(out) / (name + ".md"), md);
    draw_figures(figures, out, ctx.threads, false);
    write_provenance(out, fmt::format("study {}{}{}", name, quick ? " --quick" : "", scene ? " --scene " + scene->scene_file : ""), ctx, start);
  } catch (const std::exception& e) {
    return fail("study", e, together);
  }
  return 0;
}

int report_command(bool quick, int threads, const std::string& out, const std::string& scenes_dir) {
  const bool writer = ranks::rank() == 0;
  const fs::path target = fs::absolute(out).lexically_normal();
  const fs::path parent = target.parent_path();
  fs::path staging;
  std::unique_ptr<interrupt::Temporary> staging_guard;
  bool usable = true;
  if (writer) try {
    // the old report is replaced, never a directory that is something else (a source folder, a home)
    if (fs::exists(target) && !(fs::is_directory(target) && (fs::is_empty(target) || fs::exists(target / report_marker))))
      throw std::runtime_error(fmt::format("{}: exists and is not a stepwise report (no {} listing what a report wrote); refusing to "
                                           "write into it: give a new or empty directory", target.string(), report_marker));
    ensure_writable_directory(parent);
    // room for the whole new report beside the old one (which stays until the new one is complete)
    if (const auto free_bytes = free_bytes_at(parent.string()); free_bytes && *free_bytes < report_bytes(quick))
      throw std::runtime_error(fmt::format("{}: {:.3g} MB free, and the {}report takes about {:.0f} MB (its tables, figures, pictures and videos, "
                                           "beside the old report until the new one is complete): free some space or write it elsewhere",
                                           parent.string(), *free_bytes / 1e6, quick ? "quick " : "", report_bytes(quick) / 1e6));
    // the staging directories of reports killed outright (ours by name, their process gone)
    interrupt::remove_stale(parent);
    // the report is built beside its target and swapped in at the end
    std::string pattern = (parent / fmt::format(".{}{}XXXXXX", target.filename().string(), interrupt::temporary_tag())).string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error(fmt::format("{}: cannot create a staging directory", parent.string()));
    staging = pattern;
    staging_guard = std::make_unique<interrupt::Temporary>(staging);
    // mkdtemp's 0700 widened to what a directory made the usual way gets
    fs::permissions(staging, static_cast<fs::perms>(default_mode(true)));
  } catch (const std::runtime_error& e) {
    print_error("report", fmt::format("--out: {}", e.what()));
    usable = false;
  }
  if (!ranks::all_agree(usable)) return 2;

  const auto start = std::chrono::steady_clock::now();
  const auto started = std::chrono::system_clock::now();
  Progress progress;
  if (writer) progress.set_slowness(machine_slowness());
  RankLoad load;
  StudyContext ctx{quick, threads_or_default(threads), writer ? &progress : nullptr};
  ctx.load = &load;
  std::string md;
  std::vector<std::string> findings;
  std::vector<Figure> figures;
  std::error_code ec;
  bool together = true;
  try {
    for (const auto& study : studies())
      if (!study.drawn) md += run_study(study, ctx, staging, figures, &findings);
    // the answer first: what the studies found, each linking to its evidence, then the sections
    std::string head = fmt::format("# stepwise report{}\n\n", quick ? " (quick)" : "");
    head += "Every number, table and figure below is computed by this run from the CSV files named under its section, in this directory.\n\n";
    head += "<a id=\"in-short\"></a>\n\n## In short\n\n";
    for (const auto& f : findings) head += f + "\n";
    md = head + "\n" + md;
    together = false;
    if (!writer) return 0;
    // the drawn studies on rank 0 alone: pictures and videos, drawn where the report is written
    StudyContext here = ctx;
    here.distribute = false;
    here.load = nullptr;  // the ranks' shares are the sweeps'; the pictures are rank 0's alone
    here.out = staging;
    here.scenes_dir = scenes_dir;
    for (const auto& study : studies())
      if (study.drawn) md += run_study(study, here, staging, figures, nullptr);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    md += ranks::size() == 1 ? fmt::format("---\nStudies run in {:.1f} s of wall time on {} threads.\n", seconds, ctx.threads)
                             : fmt::format("---\nStudies run in {:.1f} s of wall time on {} MPI ranks of {} threads (the pictures on rank 0).\n",
                                           seconds, ranks::size(), ctx.threads);
    write_file_atomic(staging / "report.md", md);
    draw_figures(figures, staging, ctx.threads, true);
    write_provenance(staging, quick ? "report --quick" : "report", ctx, started);
    write_report_marker(staging);
  } catch (const std::exception& e) {
    if (writer) fs::remove_all(staging, ec);
    return fail("report", e, together);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  swap_report(staging, target);
  std::cerr << fmt::format("stepwise: report written to {} in {:.1f} s\n", target.string(), seconds);
  return 0;
}

}  // namespace stepwise
