// Model adequacy: how far the small-angle pendulum can be trusted.
//
// The small-angle model has period T0 = 2 pi / w for every amplitude; the true period is
// T(theta0) = 4 K(sin(theta0/2)) / w = T0 (1 + theta0^2/16 + 11 theta0^4/3072 + ...). After N true
// periods the small-angle model is off in phase by 2 pi N (T/T0 - 1).
#pragma once

namespace stepwise {

// phase error (rad) of the small-angle model after n_periods periods of the true pendulum at amplitude theta0
double small_angle_phase_error(double theta0, double n_periods);

// the largest amplitude (rad) whose small-angle phase error after n_periods stays within phase_tolerance (rad),
// by bisection on the exact period
double small_angle_max_amplitude(double phase_tolerance, double n_periods);

}  // namespace stepwise
