// A PDE scene's own keys (model = "pde", models/pde.hpp): fields, [grid], [boundary.FIELD], [initial], [equations],
// [exact], read into Scene::pde. The formulas' own checks (names, operators) come when the model is made.
#include "scene_toml.hpp"

#include "models/equations/spec_checks.hpp"
#include "models/equations/tape.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace stepwise {
namespace {

constexpr std::array<std::string_view, 6> keys{"fields", "grid", "boundary", "initial", "equations", "exact"};

const toml::table& table_of(const toml::node& node, const Scene& scene, const std::string& key, const char* what) {
  const auto* table = node.as_table();
  if (!table) throw InputError(fmt::format("{}:{}: {}: expected a table ({})", scene.file, line_of(node), key, what));
  return *table;
}

// [grid]: x = [a, b], y = [a, b] (2-D), points = n or [nx, ny], order = 2 or 4
void grid_table(const toml::node& node, Scene& scene, PdeSpec& spec) {
  bool has_x = false;
  for (auto&& [k, value] : table_of(node, scene, "grid", "x = [a, b], points = n")) {
    const std::string name(k.str()), key = "grid." + name;
    scene.lines[key] = line_of(value);
    const std::string where = fmt::format("{}:{}: {}", scene.file, line_of(value), key);
    if (name == "x" || name == "y") {
      const auto* ends = value.as_array();
      if (!ends || ends->size() != 2) throw InputError(fmt::format("{}: expected the domain's two ends, [a, b]", where));
      const size_t axis = name == "x" ? 0 : 1;
      spec.domain[axis] = {number(*ends->get(0), scene, key), number(*ends->get(1), scene, key)};
      if (!(spec.domain[axis][1] > spec.domain[axis][0]))
        throw InputError(fmt::format("{}: [{}, {}] is empty or backwards: the domain's ends in increasing order", where, spec.domain[axis][0], spec.domain[axis][1]));
      spec.domain_where[axis] = where;
      has_x = has_x || axis == 0;
      if (axis == 1) spec.dimension = 2;
    } else if (name == "points") {
      spec.points_where = where;
      const auto whole = [&](const toml::node& n) {
        const auto* i = n.as_integer();
        if (!i || i->get() < 1 || i->get() > 1'000'000'000) throw InputError(fmt::format("{}: expected a whole number of nodes", where));
        return static_cast<int>(i->get());
      };
      if (const auto* both = value.as_array()) {
        if (both->size() != 2) throw InputError(fmt::format("{}: expected points = n, or [nx, ny] in 2-D", where));
        spec.points = {whole(*both->get(0)), whole(*both->get(1))};
      } else {
        spec.points = {whole(value), whole(value)};
      }
    } else if (name == "order") {
      const auto* i = value.as_integer();
      if (!i || (i->get() != 2 && i->get() != 4)) throw InputError(fmt::format("{}: the central stencils' order is 2 or 4", where));
      spec.order = static_cast<int>(i->get());
      spec.order_where = where;
    } else {
      throw InputError(fmt::format("{}: unknown key (grid has x, y, points, order)", where));
    }
  }
  if (!has_x) throw InputError(fmt::format("{}:{}: grid: needs x = [a, b]", scene.file, line_of(node)));
  if (spec.points_where.empty()) throw InputError(fmt::format("{}:{}: grid: needs points = n", scene.file, line_of(node)));
  if (spec.order_where.empty()) spec.order_where = fmt::format("{}:{}: grid.order", scene.file, line_of(node));
}

// [boundary.FIELD]: x = "periodic" (y likewise), or per side left/right/bottom/top = { value = "..." } or
// { derivative = "..." }
PdeBoundary boundary_table(const std::string& field, const toml::node& node, Scene& scene) {
  const std::string key = "boundary." + field;
  PdeBoundary b;
  b.where = fmt::format("{}:{}: {}", scene.file, line_of(node), key);
  constexpr std::array<std::string_view, 4> sides{"left", "right", "bottom", "top"};
  for (auto&& [k, value] : table_of(node, scene, key, "x = \"periodic\", or left = { value = \"...\" }, ...")) {
    const std::string name(k.str()), full = key + "." + name;
    const std::string where = fmt::format("{}:{}: {}", scene.file, line_of(value), full);
    if (name == "x" || name == "y") {
      const auto* text = value.as_string();
      if (!text || text->get() != "periodic") throw InputError(fmt::format("{}: an axis's condition is \"periodic\" (else give each side's)", where));
      b.periodic[name == "x" ? 0 : 1] = true;
      continue;
    }
    const auto side = std::find(sides.begin(), sides.end(), name);
    if (side == sides.end()) throw InputError(fmt::format("{}: unknown key (a boundary has x, y = \"periodic\", or left, right, bottom, top)", where));
    const auto* condition = value.as_table();
    if (!condition || condition->size() != 1)
      throw InputError(fmt::format("{}: expected {{ value = \"formula\" }} (Dirichlet) or {{ derivative = \"formula\" }} (Neumann)", where));
    for (auto&& [kind, formula] : *condition) {
      const std::string what(kind.str());
      if (what != "value" && what != "derivative") throw InputError(fmt::format("{}.{}: expected value (Dirichlet) or derivative (Neumann)", where, what));
      b.sides[static_cast<size_t>(side - sides.begin())] =
          PdeSide{what == "value" ? PdeSide::Kind::value : PdeSide::Kind::derivative, formula_of(formula, scene, full + "." + what, field)};
    }
  }
  return b;
}

}  // namespace

bool pde_key(std::string_view key) { return std::find(keys.begin(), keys.end(), key) != keys.end(); }

void pde_entry(const std::string& key, const toml::node& node, Scene& scene) {
  if (!scene.pde) scene.pde.emplace();
  PdeSpec& spec = *scene.pde;
  spec.file = scene.file;
  scene.lines[key] = line_of(node);
  if (key == "fields") {
    const auto* array = node.as_array();
    if (!array || array->empty()) throw InputError(fmt::format("{}:{}: fields: expected an array of names, [\"u\", \"v\"]", scene.file, line_of(node)));
    spec.fields_where = fmt::format("{}:{}: fields", scene.file, line_of(node));
    for (size_t i = 0; i < array->size(); ++i) {
      const auto* name = array->get(i)->as_string();
      if (!name || !equations::identifier(name->get()) || equations::reserved(name->get()) || name->get() == "x" || name->get() == "y" || name->get() == "t")
        throw InputError(fmt::format("{}:{}: fields[{}]: expected a name (a letter, then letters, digits or _; not x, y, t or a function)", scene.file,
                                     line_of(*array->get(i)), i));
      if (std::find(spec.fields.begin(), spec.fields.end(), name->get()) != spec.fields.end())
        throw InputError(fmt::format("{}:{}: fields[{}]: '{}' named twice", scene.file, line_of(*array->get(i)), i, name->get()));
      spec.fields.push_back(name->get());
    }
  } else if (key == "grid") {
    grid_table(node, scene, spec);
  } else if (key == "boundary") {
    for (auto&& [field, table] : table_of(node, scene, key, "[boundary.FIELD] tables"))
      spec.boundary.emplace_back(std::string(field.str()), boundary_table(std::string(field.str()), table, scene));
  } else {
    for (auto&& [k, value] : table_of(node, scene, key, "field = \"formula\"")) {
      const std::string name(k.str()), full = key + "." + name;
      scene.lines[full] = line_of(value);
      (key == "initial" ? spec.initial : key == "equations" ? spec.equations : spec.exact).push_back(formula_of(value, scene, full, name));
    }
  }
}

void finish_pde(Scene& scene) {
  if (!scene.pde || scene.pde->fields.empty()) throw InputError(fmt::format("{}: fields: missing (a pde scene names its fields: fields = [\"u\"])", scene.file));
  PdeSpec& spec = *scene.pde;
  if (spec.points_where.empty()) throw InputError(fmt::format("{}: grid: missing ([grid] x = [a, b], points = n)", scene.file));
  for (const auto& [field, boundary] : spec.boundary)
    if (std::find(spec.fields.begin(), spec.fields.end(), field) == spec.fields.end())
      throw InputError(fmt::format("{}: '{}' is not a field (fields: {})", boundary.where, field, fmt::join(spec.fields, ", ")));
  for (const auto& [field, boundary] : spec.boundary)
    if (spec.dimension == 1 && (boundary.periodic[1] || boundary.sides[2] || boundary.sides[3]))
      throw InputError(fmt::format("{}: y, bottom or top in a 1-D scene (its [grid] has no y)", boundary.where));
  spec.parameters = scene.parameters;
}

}  // namespace stepwise
