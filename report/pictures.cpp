#include "pictures.hpp"

#include "atomic_write.hpp"
#include "csv.hpp"
#include "process.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <iostream>

namespace stepwise {

namespace fs = std::filesystem;

namespace {

struct Picture {
  const char* scene;
  const char* caption;
};

// the seeds' scenes, one of each kind of shape
constexpr Picture pictured[] = {
    {"bouncing-ball", "The seeds' OpenGL example: the ball over the ground line, restitution 0.8 (cvode-bdf with its impacts as events)."},
    {"pendulum", "The pendulum, its bob's path traced."},
    {"flow-particle", "A particle carried by the velocity field (x, sin y), its path traced."},
    {"particles-in-box", "Particles bouncing in a box under gravity."},
    {"flag-on-pole", "The flag: a mass-spring sheet on a pole in the wind, implicit Euler on CHOLMOD; red in front, blue behind."},
    {"stack-collapse", "A wall of boxes hit by a ball: contacts and friction by sequential impulses."},
    {"water-drop", "Height-field water after a drop: the floor lit by the photon-map caustic, the surface refracting and reflecting."},
};

}  // namespace

std::string pictures_section(const fs::path& dir, const fs::path& scenes_dir, bool quick) {
  const int frames = quick ? 16 : 60;
  const std::string size = quick ? "480x270" : "640x360";
  Table table{{"scene", "model", "method", "frames", "t_end", "draw_ms_per_frame", "status", "renderer"}, {}};
  std::string body;
  for (const auto& [scene, caption] : pictured) {
    const fs::path out = dir / "pictures" / scene;
    std::cerr << fmt::format("stepwise report: drawing {}\n", scene);
    std::string why;
    const auto status = run_process({"/proc/self/exe", "render", (scenes_dir / (std::string(scene) + ".toml")).string(), "--frames",
                                     std::to_string(frames), "--size", size, "--out", out.string()},
                                    &why);
    if (!status || *status != 0)
      throw std::runtime_error(fmt::format("stepwise render {} failed ({}): the pictures were not drawn", scene,
                                           status ? fmt::format("exit status {}", *status) : why));
    std::ifstream in(out / "render.json");
    const auto j = nlohmann::json::parse(in);
    const auto& shown = j["frames"].back();
    const double per_frame = j["draw_seconds"].get<double>() * 1000 / static_cast<double>(j["frames"].size());
    table.rows.push_back({std::string(scene), j["model"].get<std::string>(), j["method"].get<std::string>(),
                          static_cast<double>(j["frames"].size()), shown["t"].get<double>(), per_frame,
                          j["status"].get<std::string>(), j["renderer"].get<std::string>()});
    const std::string still = fmt::format("pictures/{}/{}", scene, shown["file"].get<std::string>());
    body += fmt::format("### {}\n\n{} The last frame, t = {:.3g} s:\n\n![{}]({})\n\n", scene, caption, shown["t"].get<double>(), scene, still);
    if (fs::exists(out / "animation.gif"))
      body += fmt::format("The whole run ([MP4](pictures/{0}/animation.mp4)):\n\n![{0} animation](pictures/{0}/animation.gif)\n\n", scene);
  }
  write_file_atomic(dir / "pictures.csv", to_csv(table));
  std::string md = "## Pictures\n\n";
  md += fmt::format("Each scene run through its own method and drawn headlessly by `stepwise render` ({} frames at {}, OpenGL on {}). "
                    "Data: [pictures.csv](pictures.csv).\n\n",
                    frames, size, std::get<std::string>(table.rows.front().back()));
  md += "| scene | method | frames | draw ms per frame |\n|---|---|---|---|\n";
  for (const auto& row : table.rows)
    md += fmt::format("| {} | {} | {:.0f} | {:.1f} |\n", std::get<std::string>(row[0]), std::get<std::string>(row[2]), std::get<double>(row[3]),
                      std::get<double>(row[5]));
  return md + "\n" + body;
}

}  // namespace stepwise
