// Convergence sweep of a fixed-step method: error at t_end against dt over successive halvings.
#pragma once

#include <stepwise/run/measure.hpp>

#include <vector>
#include <tuple>

namespace stepwise {

struct ConvergenceSweep {
  std::vector<double> dt;           // each step size tried, coarsest first: halvings, or for orders above 5
                                    // twice as many refinements by sqrt(2), so the error stays in range
  std::vector<Measured> runs;       // one run per dt
  std::vector<double> fit_dt, fit_error;  // the points in the asymptotic range above round-off, which the slope is fitted to
  double observed_order = 0;        // least-squares slope of log error against log dt
  static auto fields(auto& s) { return std::tie(s.dt, s.runs, s.fit_dt, s.fit_error, s.observed_order); }
};

// the coarsest step of a sweep for a method of this order, for a scene whose fastest time scale is
// time_scale (s): the fraction shrinks with the order so that the error starts near 1e-3 and stays above
// round-off for at least four halvings (chosen by measurement on the pendulum, flow-field and projectile scenes);
// a power of two of time_scale, so that t_end is a whole number of steps
double coarse_dt(const Method& method, double time_scale);

// run model with method from dt = coarse down to coarse / 2^halvings, to t_end
// the steps a convergence sweep runs, from `coarse` down: halving `halvings` times, by sqrt(2) for a method of
// order above 5 (its error would otherwise fall from the asymptotic range to round-off in a halving or two)
std::vector<double> convergence_steps(const Method& method, int halvings, double coarse);

// errors against the model's exact solution, or against `reference` (the state at t_end) where given
ConvergenceSweep convergence_sweep(const Model& model, const Method& method, double t_end, int halvings,
                                   double coarse, const Eigen::VectorXd* reference = nullptr);

}  // namespace stepwise
