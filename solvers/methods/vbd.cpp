// vbd and vbd-chebyshev: Vertex Block Descent (solvers/vertex_block_descent.hpp, its VbdStepper) as fixed-step methods on a
// mass-spring system. With enough sweeps the step is backward Euler's; with few, less.
#include "solvers/method_table.hpp"
#include "solvers/vertex_block_descent.hpp"

namespace stepwise {

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
        .substepped = true,
        .make =
            [chebyshev](const Method& method, const StepControl& control) {
              return std::make_unique<FixedStepIntegrator>(method, control, [control, chebyshev](const CountedSystem& system) {
                return std::make_unique<VbdStepper>(system, control, chebyshev ? control.chebyshev_rho : 0.0, chebyshev ? "vbd-chebyshev" : "vbd");
              });
            },
    });
}

}  // namespace stepwise
