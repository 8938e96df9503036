// vbd and vbd-chebyshev: Vertex Block Descent (solvers/vertex_block_descent.hpp, its VbdStepper) as fixed-step methods on a
// mass-spring system. With enough sweeps the step is backward Euler's; with few, less.
#include "solvers/method_table.hpp"
#include "solvers/vertex_block_descent.hpp"

namespace stepwise {

std::vector<MethodOption> vbd_options(bool threads, bool chebyshev) {
  std::vector<MethodOption> options{
      {.name = "substeps", .max = max_substeps, .fallback = 1, .help = "backward Euler steps a step, each swept on its own"},
      {.name = "iterations", .max = max_substeps, .fallback = 4, .help = "node sweeps a substep"},
      // the inertial start by default: on the gusting flag the paper's adaptive guess (along the other forces, the wind's
      // among them) left the step 45 times as far above G's minimum after 1 sweep and the run 7 times as far off
      // backward Euler's (cloth_solvers.csv's rows of both starts)
      {.name = "start", .kind = MethodOption::Kind::choice, .fallback = 1, .help = "where a substep's sweeps start: the paper's adaptive guess or the inertial position x + h v",
       .choices = {"adaptive", "inertial"}},
  };
  if (threads)
    options.push_back({.name = "threads", .max = max_threads, .fallback = 1, .help = "threads the colour sweeps run on (the same answer on any count)"});
  // rho, the sweeps' rate (the spectral radius of the Gauss-Seidel iteration), set by hand as the VBD paper does. One
  // 1/60 s step of the flag in motion, springs and continuum: after 24 sweeps on 16^2 nodes 0.99 leaves G 34-100 times
  // closer to its minimum than 0.95 does; after 20 sweeps on 32^2, within 1.2-1.7 times of 0.995's, the best of
  // 0.97-0.995 there (a larger sheet's slowest mode is slower)
  if (chebyshev)
    options.push_back({.name = "rho", .kind = MethodOption::Kind::real, .min = 0, .max = 1, .fallback = 0.99,
                       .help = "Chebyshev's estimate of the sweeps' rate", .echo = "chebyshev_rho"});
  return options;
}

VbdSettings vbd_settings(const Method& method, const StepControl& control) {
  VbdSettings s;
  s.substeps = method.whole_setting(control, "substeps");
  s.sweeps.sweeps = method.whole_setting(control, "iterations");
  s.sweeps.threads = method.option("threads") ? method.whole_setting(control, "threads") : 1;
  s.sweeps.rho = method.option("rho") ? method.setting(control, "rho") : 0.0;
  s.start = method.whole_setting(control, "start") == 0 ? VbdStart::adaptive : VbdStart::inertial;
  return s;
}

void register_vbd_methods(MethodTable& table) {
  for (const bool chebyshev : {false, true})
    table.add({
        .name = chebyshev ? "vbd-chebyshev" : "vbd",
        .family = Family::vertex_block_descent,
        .source = Source::hand_written,
        .description = chebyshev ? "vbd with Chebyshev's semi-iterative acceleration of its sweeps (Wang 2015) at the rate --rho (0.99), an "
                                   "extrapolation that would raise the potential not taken"
                                 : "Vertex Block Descent (Chen et al. 2024): backward Euler's incremental potential by coloured Gauss-Seidel over "
                                   "the nodes, a 3 x 3 Newton step each",
        .order = {1, 1, "1"},
        .stepping = Stepping::fixed,
        .needs = needs_mass_spring,
        .options = vbd_options(true, chebyshev),
        .make =
            [](const Method& method, const StepControl& control) {
              return std::make_unique<FixedStepIntegrator>(method, control, [settings = vbd_settings(method, control), name = method.name](const CountedSystem& system) {
                return std::make_unique<VbdStepper>(system, settings, name);
              });
            },
    });
}

}  // namespace stepwise
