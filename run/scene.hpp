// A scene file (TOML): which model, its parameters, and how to run it.
//
//   model = "pendulum"
//   [parameters]   # the model's keys (see `stepwise scenes`), numbers only
//   theta0 = 1.0
//   [run]          # t_end (s), method, dt (s) or rtol/atol, output_dt (s), event_location
//   t_end = 10.0
//   method = "rk4"
//   dt = 1e-3
//   [mesh]         # for models that take a triangle mesh (particle-mesh): positions (m) and
//   vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]   # counter-clockwise faces seen from outside
//   triangles = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
//   [render]       # how `stepwise render` sees it: eye, target, up ([x, y, z], m), fov (degrees), light
//   eye = [0, -3, 2]   # (a direction towards it), color and background ([r, g, b] in 0-1), pool_depth (m)
//   variables = ["x", "v"]  [initial]  [equations]  [exact]  energy = "..."   # model = "equations" only
//   fields = ["u"]  [grid]  [boundary.u]  [initial]  [equations]  [exact]      # model = "pde" only (run/pde_scene.cpp)
#pragma once

#include <stepwise/models/equations.hpp>
#include <stepwise/models/model.hpp>
#include <stepwise/models/pde.hpp>
#include <stepwise/models/triangle_mesh.hpp>
#include <stepwise/render/camera.hpp>

#include <map>
#include <optional>
#include <stdexcept>
#include <string>

namespace stepwise {

// bad input: the message names the file, line and key; the command exits 2
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Scene {
  std::string file;                       // path as given
  std::string name;                       // file stem
  std::string model;
  Params parameters;                      // as written; validated against the model later
  std::map<std::string, int, std::less<>> lines;  // line of each key ("model", "parameters.g", "run.dt")
  std::optional<double> t_end, dt, rtol, atol, output_dt;
  std::optional<std::string> method;
  std::optional<std::string> event_location;
  std::optional<TriangleMesh> mesh;       // [mesh], indices in range and vertices finite (checked on loading)
  std::optional<std::vector<GridNode>> pins;  // [pins] nodes = [[row, column], ...], whole numbers (the model checks the grid)
  render::Look look;                      // [render]
  // model = "equations": variables, [initial], [equations], [exact], energy (models/equations.hpp), with
  // [parameters] as spec.parameters too
  std::optional<EquationsSpec> equations;
  // model = "pde": fields, [grid], [boundary.FIELD], [initial], [equations], [exact] (models/pde.hpp), with
  // [parameters] as spec.parameters too
  std::optional<PdeSpec> pde;

  // "file:line: key" where the key was written, "file: key" otherwise
  std::string where(const std::string& key) const;
};

Scene load_scene(const std::string& file);

// the same from the file's text (`file` names it in messages): what load_scene does once the file is read
Scene load_scene_text(std::string_view text, const std::string& file);

// [events.NAME] tables from TOML text, read as a scene file's are (Python's Equations(events=...) writes its dict
// so): InputError naming the file, line and key for an unknown key, a direction not one of the three, a missing
// `when`, a value of the wrong kind
std::vector<EventSpec> events_from_toml(std::string_view text, const std::string& file);

// where the scene files are: $STEPWISE_SCENES, else ./scenes, else the source tree's scenes/
std::string scenes_directory();

}  // namespace stepwise
