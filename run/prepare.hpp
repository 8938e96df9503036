// Scene to run: a scene file, --set overrides and the command line's method and step control, checked
// against the model and the method before anything runs (the run layer's first half; `stepwise run`,
// `stepwise render` and the report's pictures start here).
#pragma once

#include "run/scene.hpp"
#include "solvers/integrator.hpp"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace stepwise {

struct RunOptions {
  std::string scene_file;
  std::vector<std::string> sets;  // "key=value" overrides of scene parameters
  std::optional<std::string> method;
  std::optional<std::string> event_location;  // linear | restep
  std::optional<double> dt, rtol, atol, t_end, output_dt;
  std::string out;
};

// a scene ready to run: its model, resolved parameters, method and step control
struct PreparedRun {
  Scene scene;
  std::unique_ptr<Model> model;
  Params params;  // resolved: defaults overlaid by the scene and --set
  std::string method;
  StepControl control;
  double t_end = 0;
  double output_dt = 0;
};

// the options checked against the scene, its model and the method; InputError (or BadMethod) naming the
// file, line, key or option at fault
PreparedRun prepare_run(const RunOptions& options);

}  // namespace stepwise
