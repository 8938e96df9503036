// The scene loader's readers of TOML values, shared by its parts (run/scene.cpp, run/pde_scene.cpp): each error
// an InputError naming the file, line and key.
#pragma once

#include "scene.hpp"

#include <toml++/toml.h>

#include <string>

namespace stepwise {

int line_of(const toml::node& node);

// a finite number (a TOML float or integer)
double number(const toml::node& node, const Scene& scene, const std::string& key);

// a string value as a formula: its text, line and the file column of its first character
Formula formula_of(const toml::node& node, const Scene& scene, const std::string& key, const std::string& name);

// model = "pde"'s own keys (fields, grid, boundary, initial, equations, exact), each read into scene.pde
bool pde_key(std::string_view key);
void pde_entry(const std::string& key, const toml::node& node, Scene& scene);
// the PDE scene read whole: fields and [grid] there, [parameters] joined
void finish_pde(Scene& scene);

}  // namespace stepwise
