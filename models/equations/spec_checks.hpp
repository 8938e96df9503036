// An equations scene's shape checked before anything is parsed (names, one initial value and one equation per
// variable), and its values with the overrides (--set) applied.
#pragma once

#include "models/equations.hpp"

#include <string>
#include <utility>

namespace stepwise::equations {

// the names GiNaC's lexer reads as one symbol: a letter, then letters, digits or _ (a leading _ is a token of its
// own there, so a name starting with one could be declared and never used)
bool identifier(const std::string& name);

// the shape: names, one initial value and one equation per variable, nothing else
void check_shape(const EquationsSpec& spec);

// the spec's parameters and initial values, with the overrides (--set) applied to a parameter or an initial value
std::pair<Params, Params> resolved_values(const EquationsSpec& spec, const Params& values);

}  // namespace stepwise::equations
