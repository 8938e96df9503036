// The stepwise command line: methods, scenes, run, study, report (docs/cli.md): parsed, and the command called.
#include "cli.hpp"
#include "render_command.hpp"
#include "run_command.hpp"
#include "run/message.hpp"
#include "run/run_outputs.hpp"
#include "run/scene.hpp"

#include "models/model.hpp"
#include "report/advise.hpp"
#include "report/report.hpp"
#include "solvers/method_table.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>

namespace {

// the methods' own options on `run` or `render`: one --NAME for every method that declares NAME, its help each
// declaration's with the methods that take it, its default and range; the text as given into `given`, checked
// against the chosen method by prepare_run
void add_method_options(CLI::App& command, std::map<std::string, std::string, std::less<>>& given) {
  std::vector<const stepwise::MethodOption*> first;  // each name's first declaration, in the table's order
  for (const auto& m : stepwise::methods())
    for (const auto& o : m.options)
      if (std::none_of(first.begin(), first.end(), [&](const auto* f) { return f->name == o.name; })) first.push_back(&o);
  for (const auto* option : first) {
    // the declarations of this name, grouped by what they say
    std::vector<std::pair<std::string, std::vector<std::string_view>>> said;
    for (const auto& m : stepwise::methods())
      if (const auto* o = m.option(option->name)) {
        std::string text = fmt::format("{}{}, default {}", o->help, o->unit.empty() ? "" : fmt::format(" ({})", o->unit), o->value_text(o->fallback));
        auto at = std::find_if(said.begin(), said.end(), [&](const auto& s) { return s.first == text; });
        if (at == said.end()) said.push_back({std::move(text), {m.name}});
        else at->second.push_back(m.name);
      }
    std::string help;
    for (const auto& [text, names] : said) help += fmt::format("{}{} ({})", help.empty() ? "" : "; ", text, fmt::join(names, ", "));
    if (option->kind != stepwise::MethodOption::Kind::choice) help += fmt::format("; {}", option->range_text());
    command.add_option_function<std::string>(fmt::format("--{}", option->name), [&given, name = std::string(option->name)](const std::string& text) { given[name] = text; }, help)
        ->type_name(option->type_text());
  }
}

int list_methods(bool json) {
  if (json) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& m : stepwise::methods())
      j.push_back({{"name", m.name}, {"kind", m.description}, {"order", m.order.text}, {"source", to_string(m.source)}, {"family", to_string(m.family)},
                   {"fixed_step", m.fixed_step()}, {"adaptive", m.adaptive()}, {"options", stepwise::method_options_json(m)}});
    std::cout << j.dump(2) << '\n';
    return 0;
  }
  fmt::print("{:<18} {:<8} {:<16} {}\n", "name", "order", "source", "kind");
  for (const auto& m : stepwise::methods()) fmt::print("{:<18} {:<8} {:<16} {}\n", m.name, m.order.text, to_string(m.source), m.description);
  return 0;
}

int list_scenes() {
  const auto dir = stepwise::scenes_directory();
  if (!std::filesystem::is_directory(dir))
    throw stepwise::InputError(fmt::format("{}: the scenes directory{} is not a directory", dir, std::getenv("STEPWISE_SCENES") ? " ($STEPWISE_SCENES)" : ""));
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.path().extension() == ".toml") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  for (const auto& file : files) {
    const auto scene = stepwise::load_scene(file.string());
    if (scene.equations) {
      // a user's equations: the system as written, and the names --set takes
      std::string system;
      for (const auto& v : scene.equations->variables)
        for (const auto& f : scene.equations->equations)
          if (f.name == v) system += fmt::format("{}{}' = {}", system.empty() ? "" : ", ", f.name, f.text);
      if (system.size() > 100) system = system.substr(0, 97) + "...";
      std::vector<std::string> parameters;
      for (const auto& [key, value] : scene.equations->parameters) parameters.push_back(key);
      fmt::print("{:<24} {:<22} equations written in the scene: {}\n", file.filename().string(), scene.model, system);
      fmt::print("{:<24} parameters: {}; initial values: {}\n", "", parameters.empty() ? std::string("none") : fmt::format("{}", fmt::join(parameters, ", ")),
                 fmt::join(scene.equations->variables, ", "));
      continue;
    }
    if (scene.pde) {
      // a user's PDE: its equations as written, its grid, and the names --set takes
      std::string system;
      for (const auto& f : scene.pde->equations) system += fmt::format("{}{}_t = {}", system.empty() ? "" : ", ", f.name, f.text);
      if (system.size() > 100) system = system.substr(0, 97) + "...";
      std::vector<std::string> parameters;
      for (const auto& [key, value] : scene.pde->parameters) parameters.push_back(key);
      parameters.insert(parameters.end(), {"points", "order"});
      fmt::print("{:<24} {:<22} a PDE written in the scene: {}\n", file.filename().string(), scene.model, system);
      fmt::print("{:<24} parameters: {}\n", "", fmt::join(parameters, ", "));
      continue;
    }
    const auto* model = stepwise::find_model(scene.model);
    std::string keys;
    if (model)
      for (const auto& p : model->params) keys += fmt::format("{}{} [{}]", keys.empty() ? "" : ", ", p.key, p.unit);
    fmt::print("{:<24} {:<22} {}\n", file.filename().string(), scene.model, model ? std::string(model->description) : "unknown model");
    if (model) fmt::print("{:<24} parameters: {}\n", "", keys);
  }
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{"stepwise: the numerics behind physically based animation"};
  app.require_subcommand(1);

  bool json = false;
  auto* methods = app.add_subcommand("methods", "list the integration methods");
  methods->add_flag("--json", json, "machine-readable");

  auto* scenes = app.add_subcommand("scenes", "list the scenes in scenes/");

  stepwise::RunOptions run;
  auto* run_cmd = app.add_subcommand("run", "run a scene through one method");
  run_cmd->add_option("scene", run.scene_file, "scene file (TOML)")->required();
  run_cmd->add_option("--set", run.sets, "override a scene parameter, key=value");
  run_cmd->add_option("--method", run.method, "method name (see `stepwise methods`)");
  run_cmd->add_option("--dt", run.dt, "fixed step (s)");
  run_cmd->add_option("--rtol", run.rtol, "relative tolerance (adaptive)");
  run_cmd->add_option("--atol", run.atol, "absolute tolerance (adaptive)");
  run_cmd->add_option("--t-end", run.t_end, "end time (s)");
  run_cmd->add_option("--output-dt", run.output_dt, "trajectory sampling interval (s), default t_end/1000");
  run_cmd->add_option("--event-location", run.event_location,
                      "linear (the seeds' segment method, default) or restep (re-step to the root of g)");
  run_cmd->add_option("--max-steps", run.max_steps, fmt::format("steps (and output rows) the run may take (default {:.0e})", stepwise::default_max_steps));
  add_method_options(*run_cmd, run.method_options);
  run_cmd->add_option("--constraint", run.constraint, "project (the state put back on a constrained scene's constraints after each step) or baumgarte (its equations pulling a drift back), for an ODE method");
  run_cmd->add_option("--out", run.out, "output directory")->required();

  std::string study_name, study_out;
  bool study_quick = false, study_list = false;
  auto* study = app.add_subcommand("study", "run one study: " + stepwise::study_names());
  study->add_option("name", study_name, "study name (required unless --list)");
  study->add_flag("--list", study_list, "print each study's name and what it measures, a line each, and exit");
  study->add_flag("--quick", study_quick, "reduced sweep");
  study->add_option("--out", study_out, "output directory (required unless --list)");
  int study_threads = 0;
  study->add_option("--threads", study_threads, "threads the sweep's points run on (default: one per core)")->check(CLI::Range(1, stepwise::max_threads));
  stepwise::RunOptions study_scene;
  study->add_option("--scene", study_scene.scene_file, fmt::format("run the study on this scene file instead of its own ({})", stepwise::scene_studies()));
  study->add_option("--set", study_scene.sets, "override a parameter of the --scene file, key=value");

  std::string report_out;
  bool report_quick = false;
  auto* report = app.add_subcommand("report", "run every study and write the report");
  report->add_flag("--quick", report_quick, "reduced sweeps");
  report->add_option("--out", report_out, "output directory")->required();
  int report_threads = 0;
  report->add_option("--threads", report_threads, "threads the sweeps' points run on (default: one per core)")->check(CLI::Range(1, stepwise::max_threads));

  stepwise::AdviseOptions advise;
  auto* advise_cmd = app.add_subcommand("advise", "which method is cheapest for this scene at this error: a budgeted, measured sweep");
  advise_cmd->add_option("scene", advise.run.scene_file, "scene file (TOML)")->required();
  advise_cmd->add_option("--error", advise.error, "the max-norm error at t_end the method must meet")->required();
  advise_cmd->add_option("--budget", advise.budget, "wall-clock seconds the advice may take (default 30)");
  advise_cmd->add_option("--set", advise.run.sets, "override a scene parameter, key=value");
  advise_cmd->add_option("--t-end", advise.run.t_end, "end time (s)");
  advise_cmd->add_option("--threads", advise.threads, "threads the sweep runs on (default: one per core)")->check(CLI::Range(1, stepwise::max_threads));
  advise_cmd->add_option("--out", advise.out, "output directory")->required();

  stepwise::RenderOptions render;
  auto* render_cmd = app.add_subcommand("render", "draw a scene's animation headlessly (OpenGL): PNG frames, MP4 and GIF");
  render_cmd->add_option("scene", render.run.scene_file, "scene file (TOML)")->required();
  render_cmd->add_option("--set", render.run.sets, "override a scene parameter, key=value");
  render_cmd->add_option("--method", render.run.method, "method name (see `stepwise methods`)");
  render_cmd->add_option("--dt", render.run.dt, "fixed step (s)");
  render_cmd->add_option("--t-end", render.run.t_end, "end time (s): the last frame's");
  render_cmd->add_option("--max-steps", render.run.max_steps, fmt::format("steps the run may take (default {:.0e})", stepwise::default_max_steps));
  add_method_options(*render_cmd, render.run.method_options);
  render_cmd->add_option("--constraint", render.run.constraint, "project (the state put back on a constrained scene's constraints after each step) or baumgarte (its equations pulling a drift back), for an ODE method");
  render_cmd->add_option("--frames", render.frames, "frames from t = 0 to t_end (default 60)");
  render_cmd->add_option("--size", render.size, "WIDTHxHEIGHT in pixels (default 1280x720)");
  render_cmd->add_option("--backend", render.backend, "osmesa (default) or egl (Mesa surfaceless)");
  render_cmd->add_option("--out", render.out, "output directory")->required();

  // a first word that names no subcommand is said so (CLI11 would say a subcommand is required)
  if (argc > 1 && argv[1][0] != '-') {
    const auto subcommands = app.get_subcommands([](const CLI::App*) { return true; });
    if (std::none_of(subcommands.begin(), subcommands.end(), [&](const CLI::App* c) { return c->get_name() == argv[1]; })) {
      std::string names;
      for (const auto* c : subcommands) names += (names.empty() ? "" : ", ") + c->get_name();
      stepwise::print_error("", fmt::format("unknown subcommand '{}' (one of {})", argv[1], names));
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    stepwise::print_error("", e.what());
    return 2;
  }

  if (*methods) return list_methods(json);
  if (*scenes) return list_scenes();
  if (*run_cmd) return stepwise::run_command(run);
  if (*render_cmd) return stepwise::render_command(render);
  if (*advise_cmd) return stepwise::advise_command(advise);
  if (*study) {
    if (study_list) {
      for (const auto& [name, title] : stepwise::study_list()) fmt::print("{}  {}\n", name, title);
      return 0;
    }
    if (study_name.empty()) throw stepwise::InputError("name is required (`stepwise study --list` lists the studies)");
    if (study_out.empty()) throw stepwise::InputError("--out is required");
    if (study_scene.scene_file.empty() && !study_scene.sets.empty()) throw stepwise::InputError("--set: given without --scene");
    return stepwise::study_command(study_name, study_quick, study_threads, study_out,
                                   study_scene.scene_file.empty() ? std::nullopt : std::optional(study_scene));
  }
  if (*report) return stepwise::report_command(report_quick, report_threads, report_out, stepwise::scenes_directory());
  return 2;
}

}  // namespace

// the one guard: nothing escapes main. Bad input (the commands' own InputError, a file system refusing a path
// the user gave) is exit 2, anything else a failed run, exit 1; either way one line, and the outputs as the
// commands leave them (temporaries removed as their guards unwind; the previous outputs untouched)
int stepwise::command_line(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const stepwise::InputError& e) {
    stepwise::print_error("", e.what());
    return 2;
  } catch (const std::filesystem::filesystem_error& e) {
    stepwise::print_error("", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    stepwise::print_error("", "out of memory: the run needed more than this machine could give");
    return 1;
  } catch (const std::exception& e) {
    stepwise::print_error("", fmt::format("failed: {}", e.what()));
    return 1;
  } catch (...) {
    stepwise::print_error("", "failed: an unknown exception");
    return 1;
  }
}
