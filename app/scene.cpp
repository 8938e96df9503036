#include "scene.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

namespace stepwise {

std::string Scene::where(const std::string& key) const {
  const auto it = lines.find(key);
  return it == lines.end() ? fmt::format("{}: {}", file, key) : fmt::format("{}:{}: {}", file, it->second, key);
}

namespace {

int line_of(const toml::node& node) { return static_cast<int>(node.source().begin.line); }

double number(const toml::node& node, const Scene& scene, const std::string& key) {
  std::optional<double> value;
  if (const auto* f = node.as_floating_point()) value = f->get();
  else if (const auto* i = node.as_integer()) value = static_cast<double>(i->get());
  if (!value) throw InputError(fmt::format("{}:{}: {}: expected a number", scene.file, line_of(node), key));
  if (!std::isfinite(*value)) throw InputError(fmt::format("{}:{}: {}: not a finite number ({})", scene.file, line_of(node), key, *value));
  return *value;
}

}  // namespace

std::string scenes_directory() {
  if (const char* env = std::getenv("STEPWISE_SCENES")) return env;
  if (std::filesystem::is_directory("scenes")) return "scenes";
  return STEPWISE_SOURCE_DIR "/scenes";
}

Scene load_scene(const std::string& file) {
  Scene scene;
  scene.file = file;
  scene.name = std::filesystem::path(file).stem().string();
  if (!std::filesystem::is_regular_file(file)) throw InputError(fmt::format("{}: no such scene file", file));

  toml::table root;
  try {
    root = toml::parse_file(file);
  } catch (const toml::parse_error& e) {
    throw InputError(fmt::format("{}:{}:{}: malformed TOML: {}", file, e.source().begin.line, e.source().begin.column, e.description()));
  }

  for (auto&& [k, node] : root) {
    const std::string key(k.str());
    if (key == "model") {
      const auto* s = node.as_string();
      if (!s) throw InputError(fmt::format("{}:{}: model: expected a string", file, line_of(node)));
      scene.model = s->get();
      scene.lines["model"] = line_of(node);
    } else if (key == "parameters" || key == "run") {
      const auto* table = node.as_table();
      if (!table) throw InputError(fmt::format("{}:{}: {}: expected a table", file, line_of(node), key));
      for (auto&& [sub, value] : *table) {
        const std::string name(sub.str());
        const std::string full = key + "." + name;
        scene.lines[full] = line_of(value);
        if (key == "parameters") {
          scene.parameters[name] = number(value, scene, full);
        } else if (name == "method") {
          const auto* s = value.as_string();
          if (!s) throw InputError(fmt::format("{}:{}: {}: expected a string", file, line_of(value), full));
          scene.method = s->get();
        } else if (name == "event_location") {
          const auto* s = value.as_string();
          if (!s) throw InputError(fmt::format("{}:{}: {}: expected a string", file, line_of(value), full));
          scene.event_location = s->get();
        } else if (name == "t_end") scene.t_end = number(value, scene, full);
        else if (name == "dt") scene.dt = number(value, scene, full);
        else if (name == "rtol") scene.rtol = number(value, scene, full);
        else if (name == "atol") scene.atol = number(value, scene, full);
        else if (name == "output_dt") scene.output_dt = number(value, scene, full);
        else throw InputError(fmt::format("{}:{}: {}: unknown key (run takes t_end, method, dt, rtol, atol, output_dt, event_location)", file, line_of(value), full));
      }
    } else {
      throw InputError(fmt::format("{}:{}: {}: unknown key (a scene has model, [parameters], [run])", file, line_of(node), key));
    }
  }
  if (scene.model.empty()) throw InputError(fmt::format("{}: model: missing", file));
  return scene;
}

}  // namespace stepwise
