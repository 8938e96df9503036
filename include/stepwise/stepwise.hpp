// stepwise's public surface: what a program outside the repository includes after find_package(stepwise)
// (docs/library.md). Everything here is the project's own types; no backend's (SUNDIALS, GSL, CHOLMOD, FFTW,
// GL, MPI) appears in these headers or in the ones they include.
//
//   the method table and making an integrator by name   solvers/method_table.hpp: methods(), find_method(),
//                                                        make_integrator(name, StepControl)
//   a user's own system and what it may offer           solvers/ode_system.hpp: OdeSystem (size, rhs,
//                                                        autonomous) and the optional parts it may offer:
//                                                        DenseJacobian, SparseJacobian, EventSource, Projection;
//                                                        solvers/capabilities/second_order.hpp: y = (x, v)
//   a run: step control, counters, result               solvers/integrator.hpp: StepControl::fixed/adaptive,
//                                                        Integrator::integrate, RunResult, Stats, Status
//   the built-in models                                 models/model.hpp: make_model(name, params), models()
//   equations written as text                           models/equations.hpp: make_equations(spec, values)
//   a PDE written as text, on a grid                     models/pde.hpp: make_pde(spec, values), pde_grid
//   scene files and running them measured               run/scene.hpp: load_scene; run/prepare.hpp:
//                                                        prepare_run; run/measure.hpp: run_and_measure;
//                                                        run/run_outputs.hpp: a run's rows and summary.json
//   the studies on one scene, and the advice            report/studies.hpp: studies(), Study::run;
//                                                        report/report.hpp: find_study, study_scene_of;
//                                                        report/user_scene.hpp: user_study_scene;
//                                                        report/advise.hpp: advise
#pragma once

#include <stepwise/models/equations.hpp>
#include <stepwise/models/model.hpp>
#include <stepwise/models/pde.hpp>
#include <stepwise/report/advise.hpp>
#include <stepwise/report/report.hpp>
#include <stepwise/report/studies.hpp>
#include <stepwise/report/user_scene.hpp>
#include <stepwise/run/measure.hpp>
#include <stepwise/run/prepare.hpp>
#include <stepwise/run/run_outputs.hpp>
#include <stepwise/run/scene.hpp>
#include <stepwise/solvers/capabilities/second_order.hpp>
#include <stepwise/solvers/integrator.hpp>
#include <stepwise/solvers/method_table.hpp>
#include <stepwise/solvers/ode_system.hpp>

#include <string_view>

namespace stepwise {

// the installed package's version, as CMake's project() gives it ("0.1.0")
std::string_view version();

}  // namespace stepwise
