#include "scene.hpp"

#include "scene_toml.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <type_traits>
#include <vector>
#include <cstdlib>
#include <filesystem>
#include <cerrno>
#include <fstream>
#include <iterator>
#include <cstring>
#include <unistd.h>

namespace stepwise {

int line_of(const toml::node& node) { return static_cast<int>(node.source().begin.line); }

double number(const toml::node& node, const Scene& scene, const std::string& key) {
  std::optional<double> value;
  if (const auto* f = node.as_floating_point()) value = f->get();
  else if (const auto* i = node.as_integer()) value = static_cast<double>(i->get());
  if (!value) throw InputError(fmt::format("{}:{}: {}: expected a number", scene.file, line_of(node), key));
  if (!std::isfinite(*value)) throw InputError(fmt::format("{}:{}: {}: not a finite number ({})", scene.file, line_of(node), key, *value));
  return *value;
}

// the text after the opening quote or quotes
Formula formula_of(const toml::node& node, const Scene& scene, const std::string& key, const std::string& name) {
  const auto* text = node.as_string();
  if (!text) throw InputError(fmt::format("{}:{}: {}: expected a formula in quotes", scene.file, line_of(node), key));
  return Formula{name, text->get(), scene.file, key, line_of(node), static_cast<int>(node.source().begin.column) + 1};
}

std::string Scene::where(const std::string& key) const {
  const auto it = lines.find(key);
  return it == lines.end() ? fmt::format("{}: {}", file, key) : fmt::format("{}:{}: {}", file, it->second, key);
}

namespace {

constexpr std::uintmax_t max_scene_bytes = 16u << 20;  // a large mesh fits in a few MiB of TOML


// an array of rows of N: finite numbers, or (T integral) non-negative whole numbers (`what` they are), each
// error naming the row and its line
template <class T, size_t N>
std::vector<std::array<T, N>> rows_of(const toml::node& node, const Scene& scene, const std::string& key, const char* what) {
  const auto* rows = node.as_array();
  if (!rows) throw InputError(fmt::format("{}:{}: {}: expected an array of rows of {} {}", scene.file, line_of(node), key, N, what));
  std::vector<std::array<T, N>> out;
  for (size_t r = 0; r < rows->size(); ++r) {
    const toml::node& row_node = *rows->get(r);
    const std::string at = fmt::format("{}[{}]", key, r);
    const auto* row = row_node.as_array();
    if (!row || row->size() != N) throw InputError(fmt::format("{}:{}: {}: expected {} {}", scene.file, line_of(row_node), at, N, what));
    std::array<T, N> values{};
    for (size_t c = 0; c < N; ++c) {
      const toml::node& cell = *row->get(c);
      if constexpr (std::is_integral_v<T>) {
        const auto* i = cell.as_integer();
        if (!i) throw InputError(fmt::format("{}:{}: {}: expected whole {}", scene.file, line_of(cell), at, what));
        if (i->get() < 0 || i->get() > std::numeric_limits<int>::max())
          throw InputError(fmt::format("{}:{}: {}: {} {} out of range", scene.file, line_of(cell), at, what, i->get()));
        values[c] = static_cast<T>(i->get());
      } else {
        values[c] = number(cell, scene, at);
      }
    }
    out.push_back(values);
  }
  return out;
}

// [render]: the camera, the light, colours and the pool's depth (render/camera.hpp's Look)
render::Look render_table(const toml::node& node, Scene& scene) {
  const auto* table = node.as_table();
  if (!table) throw InputError(fmt::format("{}:{}: render: expected a table", scene.file, line_of(node)));
  render::Look look;
  for (auto&& [k, entry] : *table) {
    const toml::node& value = entry;  // (a lambda may not capture a structured binding before C++20's clang 16)
    const std::string name(k.str()), full = "render." + name;
    scene.lines[full] = line_of(value);
    const auto vector = [&]() {
      const auto* array = value.as_array();
      if (!array || array->size() != 3) throw InputError(fmt::format("{}:{}: {}: expected three numbers [x, y, z]", scene.file, line_of(value), full));
      Eigen::Vector3d v;
      for (size_t c = 0; c < 3; ++c) v[static_cast<Eigen::Index>(c)] = number(*array->get(c), scene, full);
      return v;
    };
    const auto direction = [&]() {
      const Eigen::Vector3d v = vector();
      if (!(v.norm() > 0)) throw InputError(fmt::format("{}:{}: {}: a direction cannot be zero", scene.file, line_of(value), full));
      return v;
    };
    const auto colour = [&]() {
      const Eigen::Vector3d v = vector();
      if ((v.array() < 0).any() || (v.array() > 1).any())
        throw InputError(fmt::format("{}:{}: {}: colour components lie in [0, 1]", scene.file, line_of(value), full));
      return Eigen::Vector3f(v.cast<float>());
    };
    if (name == "eye") look.eye = vector();
    else if (name == "target") look.target = vector();
    else if (name == "up") look.up = direction();
    else if (name == "light") look.light = direction();
    else if (name == "color") look.color = colour();
    else if (name == "background") look.background = colour();
    else if (name == "fov") {
      look.fov_deg = number(value, scene, full);
      if (!(look.fov_deg > 1 && look.fov_deg < 170)) throw InputError(fmt::format("{}:{}: {}: field of view {} is not within (1, 170) degrees", scene.file, line_of(value), full, look.fov_deg));
    } else if (name == "pool_depth") {
      look.pool_depth = number(value, scene, full);
      if (!(*look.pool_depth > 0)) throw InputError(fmt::format("{}:{}: {}: must be positive", scene.file, line_of(value), full));
    } else {
      throw InputError(fmt::format("{}:{}: {}: unknown key (render takes eye, target, up, fov, light, color, background, pool_depth)", scene.file, line_of(value), full));
    }
  }
  if (look.eye && look.target && (*look.eye - *look.target).norm() == 0)
    throw InputError(fmt::format("{}: the eye and the target are the same point", scene.where("render.eye")));
  return look;
}

// [mesh]: vertices and triangles, every index naming a vertex
TriangleMesh mesh_table(const toml::node& node, Scene& scene) {
  const auto* table = node.as_table();
  if (!table) throw InputError(fmt::format("{}:{}: mesh: expected a table", scene.file, line_of(node)));
  const toml::node* vertices = table->get("vertices");
  const toml::node* triangles = table->get("triangles");
  for (auto&& [k, value] : *table)
    if (k.str() != "vertices" && k.str() != "triangles")
      throw InputError(fmt::format("{}:{}: mesh.{}: unknown key (a mesh has vertices and triangles)", scene.file, line_of(value), k.str()));
  if (!vertices || !triangles) throw InputError(fmt::format("{}:{}: mesh: needs both vertices and triangles", scene.file, line_of(node)));
  const auto v = rows_of<double, 3>(*vertices, scene, "mesh.vertices", "coordinates");
  const auto f = rows_of<int, 3>(*triangles, scene, "mesh.triangles", "vertex indices");
  // a coordinate's cube (a volume) must not overflow: 1e100 m is far past any scene and far below that
  constexpr double farthest = 1e100;
  for (size_t r = 0; r < v.size(); ++r)
    for (const double x : v[r])
      if (!(std::abs(x) <= farthest))
        throw InputError(fmt::format("{}:{}: mesh.vertices[{}]: coordinate {} is beyond {:.0e} m, where the mesh's areas and volume overflow",
                                     scene.file, line_of(*vertices->as_array()->get(r)), r, x, farthest));
  TriangleMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  mesh.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (size_t r = 0; r < v.size(); ++r)
    for (int c = 0; c < 3; ++c) mesh.vertices(static_cast<Eigen::Index>(r), c) = v[r][static_cast<size_t>(c)];
  for (size_t r = 0; r < f.size(); ++r)
    for (int c = 0; c < 3; ++c) {
      const int index = f[r][static_cast<size_t>(c)];
      if (index >= static_cast<int>(v.size()))
        throw InputError(fmt::format("{}:{}: mesh.triangles[{}]: vertex index {} out of range ({} vertices)", scene.file,
                                     line_of(*triangles->as_array()->get(r)), r, index, v.size()));
      mesh.faces(static_cast<Eigen::Index>(r), c) = index;
    }
  scene.lines["mesh"] = line_of(node);
  return mesh;
}

// [pins]: nodes = [[row, column], ...]
std::vector<GridNode> pins_table(const toml::node& node, Scene& scene) {
  const auto* table = node.as_table();
  if (!table) throw InputError(fmt::format("{}:{}: pins: expected a table", scene.file, line_of(node)));
  for (auto&& [k, value] : *table)
    if (k.str() != "nodes") throw InputError(fmt::format("{}:{}: pins.{}: unknown key (pins has nodes = [[row, column], ...])", scene.file, line_of(value), k.str()));
  const toml::node* nodes = table->get("nodes");
  if (!nodes) throw InputError(fmt::format("{}:{}: pins: needs nodes = [[row, column], ...]", scene.file, line_of(node)));
  scene.lines["pins"] = line_of(*nodes);
  return rows_of<int, 2>(*nodes, scene, "pins.nodes", "grid indices (row, column)");
}

// the keys of an equations scene (model = "equations"), each a table or value of its own
constexpr std::array<std::string_view, 6> equations_keys{"variables", "initial", "equations", "exact", "energy", "events"};
bool equations_key(std::string_view key) {
  const std::string_view top = key.substr(0, key.find('.'));
  return std::find(equations_keys.begin(), equations_keys.end(), top) != equations_keys.end();
}


// an [events.NAME] table: InputError naming the file, line and key for an unknown key, a direction not one of
// the three, a missing `when`, a value of the wrong kind
EventSpec event_spec(const std::string& name, const toml::node& node, const std::string& file) {
  const std::string key = "events." + name;
  const auto* table = node.as_table();
  if (!table) throw InputError(fmt::format("{}:{}: {}: expected a table (when = \"...\", direction, action, terminal, rest)", file, line_of(node), key));
  Scene scene;
  scene.file = file;
  EventSpec e;
  e.name = name;
  e.where = fmt::format("{}:{}: {}", file, line_of(node), key);
  bool has_when = false;
  for (auto&& [k, value] : *table) {
    const std::string sub(k.str()), full = key + "." + sub;
    if (sub == "when") {
      e.when = formula_of(value, scene, full, name);
      has_when = true;
    } else if (sub == "direction") {
      const auto* s = value.as_string();
      const std::string d = s ? s->get() : "";
      if (d != "rising" && d != "falling" && d != "either")
        throw InputError(fmt::format("{}:{}: {}: expected \"rising\", \"falling\" or \"either\"{}", file, line_of(value), full, s ? fmt::format(", not \"{}\"", d) : ""));
      e.direction = d == "rising" ? 1 : d == "falling" ? -1 : 0;
    } else if (sub == "action") {
      const auto* action = value.as_table();
      if (!action) throw InputError(fmt::format("{}:{}: {}: expected a table of variable = \"formula\" ({{ v = \"-e*v\" }})", file, line_of(value), full));
      for (auto&& [variable, formula] : *action)
        e.action.push_back(formula_of(formula, scene, full + "." + std::string(variable.str()), std::string(variable.str())));
    } else if (sub == "terminal") {
      const auto* b = value.as_boolean();
      if (!b) throw InputError(fmt::format("{}:{}: {}: expected true or false", file, line_of(value), full));
      e.terminal = b->get();
    } else if (sub == "rest") {
      e.rest = formula_of(value, scene, full, "rest");
    } else {
      throw InputError(fmt::format("{}:{}: {}: unknown key (an event has when, direction, action, terminal, rest)", file, line_of(value), full));
    }
  }
  if (!has_when) throw InputError(fmt::format("{}: needs when = \"formula\" (the event is where it crosses zero)", e.where));
  return e;
}

// the [events.NAME] tables in the order the file declares them (a TOML table's keys come sorted by name): events at
// one instant fire in that order
std::vector<EventSpec> events_in_file_order(const toml::table& events, const std::string& file) {
  std::vector<std::pair<const toml::node*, std::string>> declared;
  for (auto&& [name, value] : events) declared.emplace_back(&value, std::string(name.str()));
  std::stable_sort(declared.begin(), declared.end(), [](const auto& a, const auto& b) {
    const auto &x = a.first->source().begin, &y = b.first->source().begin;
    return std::pair(x.line, x.column) < std::pair(y.line, y.column);
  });
  std::vector<EventSpec> specs;
  for (const auto& [node, name] : declared) specs.push_back(event_spec(name, *node, file));
  return specs;
}

// the equations model's tables: variables, [initial], [equations], [exact], energy, [events.NAME]
void equations_entry(const std::string& key, const toml::node& node, Scene& scene) {
  if (!scene.equations) scene.equations.emplace();
  EquationsSpec& spec = *scene.equations;
  spec.file = scene.file;
  scene.lines[key] = line_of(node);
  if (key == "variables") {
    const auto* array = node.as_array();
    if (!array) throw InputError(fmt::format("{}:{}: variables: expected an array of names, [\"x\", \"v\"]", scene.file, line_of(node)));
    if (array->size() > max_equations)
      throw InputError(fmt::format("{}:{}: variables: {} variables, more than the {} an equations scene may hold", scene.file, line_of(node), array->size(), max_equations));
    spec.variables_where = fmt::format("{}:{}: variables", scene.file, line_of(node));
    for (size_t i = 0; i < array->size(); ++i) {
      const auto* name = array->get(i)->as_string();
      if (!name) throw InputError(fmt::format("{}:{}: variables[{}]: expected a name in quotes", scene.file, line_of(*array->get(i)), i));
      spec.variables.push_back(name->get());
    }
    return;
  }
  if (key == "energy") {
    spec.energy = formula_of(node, scene, key, key);
    return;
  }
  if (key == "events") {
    const auto* events = node.as_table();
    if (!events) throw InputError(fmt::format("{}:{}: events: expected tables [events.NAME]", scene.file, line_of(node)));
    spec.events = events_in_file_order(*events, scene.file);
    return;
  }
  const auto* table = node.as_table();
  if (!table) throw InputError(fmt::format("{}:{}: {}: expected a table", scene.file, line_of(node), key));
  if (table->size() > max_equations)
    throw InputError(fmt::format("{}:{}: {}: {} entries, more than the {} an equations scene may hold", scene.file, line_of(node), key, table->size(), max_equations));
  for (auto&& [k, value] : *table) {
    const std::string name(k.str()), full = key + "." + name;
    scene.lines[full] = line_of(value);
    if (key == "initial") spec.initial[name] = number(value, scene, full);
    else (key == "equations" ? spec.equations : spec.exact).push_back(formula_of(value, scene, full, name));
  }
}

}  // namespace

std::string scenes_directory() {
  if (const char* env = std::getenv("STEPWISE_SCENES")) return env;
  if (std::filesystem::is_directory("scenes")) return "scenes";
  return STEPWISE_SOURCE_DIR "/scenes";
}

Scene load_scene(const std::string& file) {
  // what the path is, said as it is: missing, a directory, a device or a pipe, unreadable, or too large to be a scene
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(file, ec);
  if (!fs::exists(status)) throw InputError(fmt::format("{}: no such scene file", file));
  if (fs::is_directory(status)) throw InputError(fmt::format("{}: is a directory, not a scene file", file));
  if (!fs::is_regular_file(status)) throw InputError(fmt::format("{}: is not a regular file (a scene is a TOML file)", file));
  if (::access(file.c_str(), R_OK) != 0) throw InputError(fmt::format("{}: cannot read the scene file: {}", file, std::strerror(errno)));
  if (const auto bytes = fs::file_size(file, ec); !ec && bytes > max_scene_bytes)
    throw InputError(fmt::format("{}: {} bytes, more than a scene file may hold ({} MiB)", file, bytes, max_scene_bytes >> 20));

  std::ifstream in(file, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(fmt::format("{}: cannot read the scene file", file));
  return load_scene_text(text, file);
}

std::vector<EventSpec> events_from_toml(std::string_view text, const std::string& file) {
  toml::table root;
  try {
    root = toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    throw InputError(fmt::format("{}:{}:{}: malformed TOML: {}", file, e.source().begin.line, e.source().begin.column, e.description()));
  }
  std::vector<EventSpec> events;
  for (auto&& [k, node] : root) {
    if (k.str() != "events") throw InputError(fmt::format("{}:{}: {}: unknown key (expected [events.NAME] tables)", file, line_of(node), k.str()));
    const auto* table = node.as_table();
    if (!table) throw InputError(fmt::format("{}:{}: events: expected tables [events.NAME]", file, line_of(node)));
    events = events_in_file_order(*table, file);
  }
  return events;
}

Scene load_scene_text(std::string_view text, const std::string& file) {
  Scene scene;
  scene.file = file;
  scene.name = std::filesystem::path(file).stem().string();
  toml::table root;
  try {
    root = toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    throw InputError(fmt::format("{}:{}:{}: malformed TOML: {}", file, e.source().begin.line, e.source().begin.column, e.description()));
  }

  // a PDE scene's [initial], [equations] and [exact] hold formulas of its fields: which model it is, first
  const auto* model = root.get("model");
  const bool pde = model && model->as_string() && model->as_string()->get() == "pde";
  for (auto&& [k, node] : root) {
    const std::string key(k.str());
    if (pde && pde_key(key)) {
      pde_entry(key, node, scene);
    } else if (key == "model") {
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
    } else if (key == "mesh") {
      scene.mesh = mesh_table(node, scene);
    } else if (key == "pins") {
      scene.pins = pins_table(node, scene);
    } else if (key == "render") {
      scene.look = render_table(node, scene);
    } else if (equations_key(key)) {
      equations_entry(key, node, scene);
    } else {
      throw InputError(fmt::format("{}:{}: {}: unknown key (a scene has model, [parameters], [run], [mesh], [pins], [render]; an equations "
                                   "scene variables, [initial], [equations], [exact], energy; a pde scene fields, [grid], [boundary.FIELD], "
                                   "[initial], [equations], [exact])", file, line_of(node), key));
    }
  }
  if (scene.model.empty()) throw InputError(fmt::format("{}: model: missing", file));
  if (pde) {
    finish_pde(scene);
  } else if (scene.model == "equations") {
    if (!scene.equations || scene.equations->variables_where.empty())
      throw InputError(fmt::format("{}: variables: missing (an equations scene names its state: variables = [\"x\", \"v\"])", file));
    scene.equations->parameters = scene.parameters;
  } else if (scene.equations) {
    // the first of them in the file
    const auto first = std::min_element(scene.lines.begin(), scene.lines.end(), [](const auto& a, const auto& b) {
      return equations_key(a.first) != equations_key(b.first) ? equations_key(a.first) : a.second < b.second;
    });
    throw InputError(fmt::format("{}: only a scene with model = \"equations\" has variables, [initial], [equations], [exact] or energy (this is model {})",
                                 scene.where(first->first), scene.model));
  }
  return scene;
}

}  // namespace stepwise
