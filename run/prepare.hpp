// Scene to run: a scene file, --set overrides and the command line's method and step control, checked
// against the model and the method before anything runs (the run layer's first half; `stepwise run`,
// `stepwise render` and the report's pictures start here).
#pragma once

#include <stepwise/run/scene.hpp>
#include <stepwise/solvers/integrator.hpp>

#include <map>
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
  std::optional<double> max_steps;  // the steps (and output rows) a run may take; default_max_steps
  // the method's own options by name, as the user wrote them ("iterations" -> "10", "start" -> "inertial"): each
  // checked against the method's registration (solvers/method.hpp's MethodOption) into StepControl::settings
  std::map<std::string, std::string, std::less<>> method_options;
  // "project": a constrained scene's state put back on its constraints after each step; "baumgarte": its
  // equations of motion pulling a drift back (the model's baumgarte flag)
  std::optional<std::string> constraint;
  std::string out;
};

// the steps (fixed, or the adaptive cap) and output rows a run may take unless --max-steps raises it: a few
// seconds of the pendulum, minutes to hours of the grids
constexpr double default_max_steps = 1e7;

// a scene ready to run: its model, resolved parameters, method and step control
struct PreparedRun {
  Scene scene;
  std::unique_ptr<Model> model;
  Params params;  // resolved: defaults overlaid by the scene and --set
  std::string method;
  std::string method_choice;  // empty, or why this method when neither the scene nor the command line named one
  std::string constraint;     // empty, or how an ODE method is kept on the constraints ("project", "baumgarte")
  StepControl control;
  double t_end = 0;
  double output_dt = 0;
  std::string output_dt_origin;  // what set it: "--output-dt", the scene's run.output_dt, or the default
  double output_bytes = 0;  // the trajectory's size, estimated from its rows and columns
  int ranks = 1;            // the MPI ranks the run uses: 1, or under mpirun all of them for a split run (run/distributed_run.hpp)
};

// the method for a scene that names none, and why: rk4 where a step is given (`model` unused, may be null); else
// cvode-bdf where the system is stiff at its start (t_end times the fastest decay rate of its Jacobian at least
// stiffness_threshold), else tsitouras54
std::pair<std::string, std::string> default_method(const Model* model, double t_end, bool fixed_step);

// the options checked against the scene, its model and the method; InputError (or BadMethod) naming the
// file, line, key or option at fault
PreparedRun prepare_run(const RunOptions& options);

// the same for a scene already loaded (options.scene_file unused)
PreparedRun prepare_run(const RunOptions& options, Scene scene);

// the trajectory's estimated size against the space free where it goes; InputError naming what set the output
// step (--output-dt, run.output_dt, or the default of 1000 rows) and both figures when it does not fit
void check_output_fits(const std::string& out, const PreparedRun& p);

// the bytes free to an unprivileged writer on the file system that holds `path`, or its nearest existing parent
// (a directory not made yet); empty where it cannot be told
std::optional<double> free_bytes_at(const std::string& path);

}  // namespace stepwise
