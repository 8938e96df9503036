// Every tolerance the verification suite asserts, in one place, each with where it comes from.
#pragma once

namespace stepwise::tolerance {

// observed order (least-squares slope of log error against log dt over >= 4 halvings) may differ from
// the theoretical order by this much: the error constant's own O(dt) variation over the fitted range
// moves the slope by a few hundredths, well inside the band, while an order lost (p -> p-1) lies outside.
inline constexpr double order_band = 0.15;

// a convergence fit uses only errors inside (roundoff_floor, asymptotic_ceiling): above the ceiling the
// leading error term does not dominate yet (the pendulum's Euler error at 1e-1 rad is no longer linear in dt);
// below the floor, round-off accumulated as a random walk over 1e4-1e6 steps of eps |y| each is comparable
inline constexpr double roundoff_floor = 1e-12;
inline constexpr double asymptotic_ceiling = 1e-1;

// the claim: high-order adaptive methods at rtol 1e-12, atol 1e-15 are this close to the exact
// pendulum at theta0 = 170 degrees
inline constexpr double tight_adaptive_error = 1e-6;

// global error against rtol: a controller that keeps the local error of an order-p method per step
// below rtol takes steps h ~ rtol^(1/(p+1)), so the global error ~ h^p falls as rtol^(p/(p+1)) (1/2 for
// p = 1, towards 1 for high order; per unit step control gives 1). The slope may fall short of p/(p+1),
// with p the lowest order the method uses, by at most order_band.
inline constexpr double min_tolerance_slope(int p) { return static_cast<double>(p) / (p + 1) - order_band; }

// GSL rk4 estimates its error by step doubling and returns the two-half-step result: its error at h is
// that of classical RK4 at h/2, i.e. 2^4 = 16 times smaller. The ratio measured in the asymptotic range
// is within this relative band of 16 (the next error term is O(h) relative: at h = T/400 a few percent).
inline constexpr double gsl_rk4_ratio = 16.0;
inline constexpr double gsl_rk4_ratio_band = 0.10;

// symplectic Euler: the energy error is bounded (a nearby modified energy is conserved), so the largest
// error over the last tenth of a long run may not exceed that of the first tenth by more than this factor
inline constexpr double bounded_energy_growth = 1.5;

// round-off: a quantity that should hold exactly (velocities of explicit and implicit Euler without drag)
// may differ by this many ulps of its magnitude per step taken
inline constexpr double roundoff_per_step = 4.0;

// the CVODE/GSL cross-check: two adaptive codes at rtol agree to within this multiple of rtol times the
// solution's size; the global error of a tolerance-proportional code on a non-stiff problem of unit
// Lipschitz constant over unit time is a small multiple of rtol (CVODE's guide: "a factor of 10 or so")
inline constexpr double adaptive_agreement_factor = 100.0;

}  // namespace stepwise::tolerance
