#include "adequacy.hpp"

#include "models/pendulum.hpp"

#include <cmath>
#include <numbers>

namespace stepwise {

double small_angle_phase_error(double theta0, double n_periods) {
  // g and L cancel in T/T0; any positive values do
  const double ratio = pendulum_period(theta0, 1.0, 1.0) / (2 * std::numbers::pi);
  return 2 * std::numbers::pi * n_periods * (ratio - 1);
}

double small_angle_max_amplitude(double phase_tolerance, double n_periods) {
  // the phase error grows monotonically with amplitude on (0, pi)
  double lo = 0, hi = std::numbers::pi - 1e-6;  // K(k) is finite for k = sin(theta0/2) < 1
  if (small_angle_phase_error(hi, n_periods) <= phase_tolerance) return hi;
  for (int i = 0; i < 100 && hi - lo > 1e-14; ++i) {
    const double mid = 0.5 * (lo + hi);
    (small_angle_phase_error(mid, n_periods) <= phase_tolerance ? lo : hi) = mid;
  }
  return lo;
}

}  // namespace stepwise
