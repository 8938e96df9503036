#include "pictures.hpp"

#include "studies.hpp"

#include "report/cost_model.hpp"
#include "run/atomic_write.hpp"
#include "run/csv.hpp"
#include "run/message.hpp"
#include "run/prepare.hpp"
#include "run/process.hpp"
#include "run/render_scene.hpp"
#include "solvers/capabilities/contact_bodies.hpp"
#include "solvers/method_table.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>

namespace stepwise {

namespace fs = std::filesystem;

namespace {

// what a quick report changes to keep its pictures to a second or two each; the full report draws the scenes
// as they are
struct QuickChange {
  const char* scene;
  std::vector<std::string> sets;  // key=value, as --set takes them
};
const QuickChange quick_changes[] = {
    // 100 000 particles take 16 s to simulate; 10 000 take 0.8 s a frame to draw (each a sphere, on llvmpipe)
    {"particle-system", {"count=2000"}},
    {"stack-collapse", {"rows=3"}},        // a wall of 3 x 3 boxes: a third of the 3 x 5 wall's cost
    // the 32 x 32 sheets' implicit steps and the 128^2 spectral fluid take 2-3 s each; a quarter of the
    // nodes or cells ~1 s
    {"cloth-on-sphere", {"rows=16", "columns=16"}},
    {"flag", {"rows=16", "columns=16"}},
    {"flag-on-pole", {"rows=8", "columns=16"}},      // 16 x 32: 2.1 s
    {"hanging-cloth", {"rows=12", "columns=12"}},  // 24 x 24: 0.8 s
    {"shear-layer", {"size=64"}},
    // Gray-Scott's 2 x 64^2 unknowns to t = 2000 take 5 s; on a 32^2 grid 1.9 s, its rings the same
    {"gray-scott", {"points=32"}},
};

// the quick report's change to a scene's render, if any
const QuickChange* quick_change(const std::string& scene, bool quick) {
  for (const auto& change : quick_changes)
    if (quick && scene == change.scene) return &change;
  return nullptr;
}

struct Drawn {
  std::string scene;
  nlohmann::json summary;
  static auto fields(auto& s) { return std::tie(s.scene, s.summary); }
};

// a drawn scene's part of the section: its description, the change a quick report made to it, the last frame, a
// 1-D PDE's space-time picture and the animation
std::string scene_pictures(const fs::path& dir, const fs::path& scenes_dir, const std::string& scene, const nlohmann::json& j, const QuickChange* change) {
  const auto& shown = j["frames"].back();
  std::string arguments;
  if (change)
    for (const auto& set : change->sets) arguments += fmt::format("{}--set {}", arguments.empty() ? "" : " ", set);
  const std::string changed = change ? fmt::format(" (quick report: `{}`)", arguments) : "";
  const std::string still = fmt::format("pictures/{}/{}", scene, shown["file"].get<std::string>());
  const std::string fields = j.contains("fields") ? fmt::format(" (its fields {}, {})", fmt::join(j["fields"].get<std::vector<std::string>>(), ", "),
                                                                j.contains("space_time") ? "one curve above the other" : "left to right")
                                                  : "";
  std::string md = fmt::format("### {}\n\n{}{} Drawn with {}; the last frame{}, t = {:.3g} s:\n\n![{}]({})\n\n", scene,
                               scene_description(scenes_dir / (scene + ".toml")), changed, j["method"].get<std::string>(), fields,
                               shown["t"].get<double>(), scene, still);
  if (j.contains("space_time"))
    md += fmt::format("Its fields over space (along) and time (up, t = 0 at the bottom), left to right {}:\n\n![{} over space and time](pictures/{}/{})\n\n",
                      fmt::join(j["fields"].get<std::vector<std::string>>(), ", "), scene, scene, j["space_time"].get<std::string>());
  if (fs::exists(dir / "pictures" / scene / "animation.gif"))
    md += fmt::format("The whole run{1}:\n\n![{0} animation](pictures/{0}/animation.gif)\n\n", scene,
                      fs::exists(dir / "pictures" / scene / "animation.mp4") ? fmt::format(" ([MP4](pictures/{}/animation.mp4))", scene) : "");
  return md;
}

}  // namespace

std::string scene_description(const fs::path& scene_file) {
  std::ifstream in(scene_file);
  std::string line, text;
  while (std::getline(in, line) && line.starts_with('#')) {
    const auto start = line.find_first_not_of("# ");
    if (start == std::string::npos) continue;
    if (!text.empty()) text.push_back(' ');
    text.append(line, start);
  }
  return text;
}

namespace {

StudyOutput pictures(const StudyContext& ctx) {
  const fs::path& dir = ctx.out;
  const fs::path& scenes_dir = ctx.scenes_dir;
  // a quick report's animations are a preview: 8 frames each (a frame and its share of the encoding ~40 ms)
  const int frames = ctx.quick ? 8 : 60;
  const std::string size = ctx.quick ? "480x270" : "640x360";
  std::vector<std::string> scenes;
  for (const auto& entry : fs::directory_iterator(scenes_dir))
    if (entry.path().extension() == ".toml") scenes.push_back(entry.path().stem().string());
  std::sort(scenes.begin(), scenes.end());
  if (scenes.empty()) throw std::runtime_error(fmt::format("{}: no scene files to draw", scenes_dir.string()));

  // without ffmpeg the pictures are the frames alone: said once here rather than by every scene's render. A quick
  // report, a preview, shows the stills alone: each scene's animation (ffmpeg's GIF, some 0.6 s a scene, most of
  // its ffmpeg's start and palette) took two thirds of its pictures' time
  const bool animations = !ctx.quick && on_path("ffmpeg");
  if (!ctx.quick && !animations) print_error("report", "ffmpeg is not installed: the pictures are PNG frames without their animations (apt-get install ffmpeg)");
  // each scene's expected cost (report/cost_model.hpp): its run, and its frames by what they show
  std::vector<double> costs;
  // a scene whose model has nothing to draw (a user's equations: a state without a place in space) is left out
  std::vector<std::string> undrawn;
  std::erase_if(scenes, [&](const std::string& scene) {
    RunOptions run;
    run.scene_file = (scenes_dir / (scene + ".toml")).string();
    const PreparedRun p = prepare_run(run);
    if (p.model->shapes(p.model->initial_state())) return false;
    undrawn.push_back(scene);
    return true;
  });
  for (const auto& scene : scenes) {
    RunOptions run;
    run.scene_file = (scenes_dir / (scene + ".toml")).string();
    if (const QuickChange* change = quick_change(scene, ctx.quick)) run.sets = change->sets;
    const PreparedRun p = prepare_run(run);
    double balls = 0, water = 0, other = 0, shapes_bodies = 0;
    if (const auto shapes = p.model->shapes(p.model->initial_state())) {
      shapes_bodies = static_cast<double>(shapes->bodies.size() + shapes->balls.size());
      balls = static_cast<double>(shapes->balls.size());
      if (shapes->water) water = static_cast<double>(shapes->water->points) * shapes->water->points;
      for (const auto& field : shapes->fields) water += static_cast<double>(field.nx) * field.ny;
      other = static_cast<double>(shapes->bodies.size() + shapes->lines.size());
      for (const auto& sheet : shapes->surfaces) other += static_cast<double>(sheet.faces.rows());
    }
    // an adaptive run's steps from a time scale of a tenth of the run (the scenes do not say theirs; on the one
    // adaptive scene, bouncing-ball with cvode-bdf at rtol 1e-10, this is within 15% of the steps it takes, where a
    // thousandth of the run would overestimate them 100x and scale every later estimate wrong by the first point);
    // a scene's fixed part ~0.4 s (its GL context and the set-up of its run and its animation, a process's start
    // included); a contact scene's collision work by its bodies
    const Method& method = *find_method(p.method);
    const double contact = method.needs.type == needs_contact_bodies.type && p.control.dt && shapes_bodies > 0
                               ? expected_contact_ns(p.t_end / *p.control.dt, shapes_bodies)
                               : 0;
    costs.push_back(0.4e9 + expected_run_ns(method, p.control, p.t_end, p.t_end / 10, p.model->size()) + contact +
                    frames * expected_frame_ns(balls, water, other));
  }
  const auto drawn = ctx.sweep<Drawn>(scenes, [&](size_t i) {
    const std::string& scene = scenes[i];
    const fs::path out = dir / "pictures" / scene;
    // drawn here, in this sweep thread's own GL context: a scene that fails to draw fails the report, as it
    // would a `stepwise render` of it
    RenderOptions options;
    options.run.scene_file = (scenes_dir / (scene + ".toml")).string();
    options.frames = frames;
    options.size = size;
    options.out = out.string();
    options.animations = animations;
    if (const QuickChange* change = quick_change(scene, ctx.quick)) options.run.sets = change->sets;
    try {
      if (const RenderedRun drawn = render_scene(options); drawn.status != Status::ok)
        throw std::runtime_error(fmt::format("{} (frames drawn up to t = {} s)", drawn.message, drawn.t_last));
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(fmt::format("stepwise render {} failed ({}): the pictures were not drawn", scene, e.what()));
    }
    std::ifstream in(out / "render.json");
    Drawn d{scene, nlohmann::json::parse(in)};
    // the report keeps the frame it shows and the animations; the other frames (54 of a full report's 73 MB) are
    // left to `stepwise render`, which writes them all. Without ffmpeg's animation the frames are the run, and stay
    // (a quick report's preview keeps its still alone)
    if (ctx.quick || fs::exists(out / "animation.gif")) {
      const std::string shown = d.summary["frames"].back()["file"].get<std::string>();
      for (const auto& entry : fs::directory_iterator(out))
        if (const std::string name = entry.path().filename().string(); name.starts_with("frame_") && name.ends_with(".png") && name != shown)
          fs::remove(entry.path());
    }
    return d;
  }, costs);

  Table table{{"scene", "model", "method", "frames", "t_end", "draw_ms_per_frame", "status", "renderer"}, {}};
  std::string body;
  for (const auto& [scene, j] : drawn) {
    const auto& shown = j["frames"].back();
    const double per_frame = j["draw_seconds"].get<double>() * 1000 / static_cast<double>(j["frames"].size());
    table.rows.push_back({scene, j["model"].get<std::string>(), j["method"].get<std::string>(), static_cast<double>(j["frames"].size()),
                          shown["t"].get<double>(), per_frame, j["status"].get<std::string>(), j["renderer"].get<std::string>()});
    body += scene_pictures(dir, scenes_dir, scene, j, quick_change(scene, ctx.quick));
  }
  std::string md = fmt::format("Every scene run through its own method and drawn headlessly as `stepwise render` draws it ({} frames at {}, OpenGL on {}; "
                    "the report keeps the last frame{}, `stepwise render` every frame).{}\n\n",
                    frames, size, std::get<std::string>(table.rows.front().back()),
                    ctx.quick ? " (a quick report draws no animations: the full report's are GIFs and MP4s)" : " and the animations",
                    undrawn.empty() ? std::string()
                                    : fmt::format(" Not drawn, having nothing in space to show (a user's equations): {}.", fmt::join(undrawn, ", ")));
  md += markdown_table(table, {{"scene", "scene"},
                               {"method", "method"},
                               {"frames", "frames", shown_as("{:.0f}")},
                               {"draw_ms_per_frame", "draw ms per frame", shown_as("{:.1f}")}});
  StudyOutput out;
  out.markdown = md + "\n" + body;
  out.tables = {{"pictures", std::move(table)}};
  return out;
}

}  // namespace

Study pictures_study() { return {.name = "pictures", .title = "Pictures: every scene rendered, the water with its caustic", .run = pictures, .drawn = true}; }

}  // namespace stepwise
