#include "spec_checks.hpp"

#include "models/equations/tape.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <regex>
#include <set>
#include <vector>

namespace stepwise::equations {

bool identifier(const std::string& name) { return std::regex_match(name, std::regex("[A-Za-z][A-Za-z0-9_]*")); }

void check_shape(const EquationsSpec& spec) {
  const size_t n = spec.variables.size();
  if (n == 0) throw BadEquations(fmt::format("{}: the system is empty (variables = [\"x\", ...] names the state)", spec.variables_where));
  if (n > max_equations)
    throw BadEquations(fmt::format("{}: {} variables, more than the {} an equations scene may hold", spec.variables_where, n, max_equations));
  std::set<std::string, std::less<>> seen;
  for (const auto& name : spec.variables) {
    if (!identifier(name)) throw BadEquations(fmt::format("{}: '{}' is not a name (a letter, then letters, digits or _)", spec.variables_where, name));
    if (reserved(name)) throw BadEquations(fmt::format("{}: the variable '{}' would shadow {}", spec.variables_where, name, name == "t" ? "the time t" : "a function or constant of the formulas"));
    if (!seen.insert(name).second) throw BadEquations(fmt::format("{}: the variable '{}' is named twice", spec.variables_where, name));
  }
  for (const auto& [name, value] : spec.parameters) {
    const std::string where = fmt::format("{}: parameters.{}", spec.file, name);
    if (!identifier(name)) throw BadEquations(fmt::format("{}: '{}' is not a name a formula can use (a letter, then letters, digits or _)", where, name));
    if (reserved(name)) throw BadEquations(fmt::format("{}: the parameter '{}' would shadow {}", where, name, name == "t" ? "the time t" : "a function or constant of the formulas"));
    if (seen.count(name)) throw BadEquations(fmt::format("{}: '{}' is both a variable and a parameter", where, name));
  }
  const auto check_cover = [&](const std::vector<Formula>& formulas, std::string_view table, bool required) {
    for (const auto& f : formulas)
      if (!seen.count(f.name))
        throw BadEquations(fmt::format("{}: an {} for '{}', which is not a variable (variables: {}){}", f.where(), table == "equations" ? "equation" : "exact solution",
                                       f.name, fmt::join(spec.variables, ", "),
                                       f.name == "energy" ? "; an energy formula goes above the first [table], as TOML puts a key under the table before it" : ""));
    if (required || !formulas.empty())
      for (const auto& v : spec.variables)
        if (std::none_of(formulas.begin(), formulas.end(), [&](const Formula& f) { return f.name == v; }))
          throw BadEquations(fmt::format("{}: the variable '{}' has no {} ([{}] {} = \"...\")", spec.file, v, table == "equations" ? "equation" : "exact solution", table, v));
  };
  check_cover(spec.equations, "equations", true);
  check_cover(spec.exact, "exact", false);
  for (const auto& [name, value] : spec.initial)
    if (!seen.count(name)) throw BadEquations(fmt::format("{}: initial.{}: '{}' is not a variable (variables: {})", spec.file, name, name, fmt::join(spec.variables, ", ")));
  for (const auto& v : spec.variables)
    if (!spec.initial.count(v)) throw BadEquations(fmt::format("{}: the variable '{}' has no initial value ([initial] {} = ...)", spec.file, v, v));

}

std::pair<Params, Params> resolved_values(const EquationsSpec& spec, const Params& values) {
  Params parameters = spec.parameters, initial = spec.initial;
  for (const auto& [key, value] : values) {
    Params* target = parameters.count(key) ? &parameters : initial.count(key) ? &initial : nullptr;
    if (!target) {
      std::vector<std::string> names;
      for (const auto& [name, v] : parameters) names.push_back(name);
      throw BadParameter(key, fmt::format("unknown parameter '{}' of this equations scene (parameters: {}; variables: {})", key,
                                          names.empty() ? std::string("none") : fmt::format("{}", fmt::join(names, ", ")), fmt::join(spec.variables, ", ")));
    }
    if (!std::isfinite(value)) throw BadParameter(key, fmt::format("'{}' must be a finite number, got {}", key, value));
    (*target)[key] = value;
  }

  return {parameters, initial};
}

}  // namespace stepwise::equations
