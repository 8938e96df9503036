// Stability limits found where the methods fail: bisection on the step between a run that stays bounded
// and one that does not, and the limits theory predicts for the height field.
#pragma once

#include "solvers/integrator.hpp"

#include <functional>
#include <string>
#include <string_view>

namespace stepwise {

// the largest step for which is_stable holds, by bisection between a step known stable and one known not,
// to a relative width rel_width
double bisect_stability(const std::function<bool(double dt)>& is_stable, double stable, double unstable, double rel_width);

// whether `steps` fixed steps of dt by `method` from y0 keep |y|inf within 1e6 |y0|inf (a run past the limit
// grows by its largest root's modulus per step, and is stopped as diverged once past it)
bool stays_bounded(const OdeSystem& system, std::string_view method, const Eigen::VectorXd& y0, double dt, long steps);

// The seeds' stability condition for the height field, dt < (mu + sqrt(mu^2 + 32 c^2/d^2)) / (8 c^2/d^2).
// It is the algebra of solvers/wave_step.hpp with the damping taken implicitly (v (1 + mu dt) = v + c^2 Lap z dt:
// determinant 1/(1 + mu dt), condition dt^2 w^2 <= 4 + 2 mu dt) at lambda_max = 8/d^2: right at mu = 0, too
// large at mu > 0 for both seeds' schemes (wave_stable_dt, symplectic_euler_wave_dt)
double seeds_wave_condition(const WaveGridView& grid);

// One height-field grid's stability limit for `method` (wave-fd or symplectic-euler): measured by bisection
// (to tolerance::stability_bisection_width) between half and twice the derived limit, each run `steps`
// steps of a water-drop grid started from a random interior field (every mode, the highest included,
// excited); beside it the derived limit and the seeds' condition. The test and the report's table both
// come from here; wave_stays_bounded is the probe (whether a run at dt stays bounded).
std::function<bool(double dt)> wave_stays_bounded(std::string_view method, int points, double spacing, double c, double mu, long steps);
struct WaveStability {
  double measured = 0, derived = 0, seeds = 0;
};
WaveStability wave_stability(std::string_view method, int points, double spacing, double c, double mu, long steps);

}  // namespace stepwise
