// Every tolerance the verification suite asserts, in one place, each with where it comes from.
#pragma once

#include <stepwise/models/contact.hpp>
#include <stepwise/solvers/contact_solve.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace stepwise::tolerance {

// observed order (least-squares slope of log error against log dt over >= 4 halvings) may differ from
// the theoretical order by this much: the error constant's own O(dt) variation over the fitted range
// moves the slope by a few hundredths, well inside the band, while an order lost (p -> p-1) lies outside.
inline constexpr double order_band = 0.15;

// a step of an implicit method against the closed-form solution of its own equation: Newton stops when its
// last update is below 1e-12 (1 + |y|) (solvers/methods/implicit_euler.cpp), and converging quadratically it
// leaves far less than that; 1e-12 relative holds it
inline constexpr double newton_solve = 1e-12;

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

// a tableau's sums of up to 16 coefficients of size up to 36 (Verner's), each given to double precision:
// rounding leaves ~16 x 36 x eps ~ 1e-13
inline constexpr double tableau_roundoff = 1e-12;

// an error estimate err(h) = C h^k (1 + D h + ...) followed from 2 h* to the retry: the model's relative
// deviation over that range, with |D| up to k |f'| + (the forcing's frequency) ~ k + 3 per unit time on the
// controller test's y' = -y + sin(3t); a controller exponent off by one (1/(k-1)) changes the retry's error
// by 2^(-k/(k-1)) ~ 0.42-0.46, far outside
inline constexpr double error_model_deviation(double k, double h) { return (k + 3) * h; }

// the fluid's method of lines: f is projected in Fourier space, so div u of every stage and step is the
// rounding of the transforms, ~ log2(n^2) eps |grad u| per transform (12 eps at 64^2) over the few transforms
// a stage takes and the steps' sums: 1e-12 of max |grad u| (the figure asked) holds with room
inline constexpr double spectral_divergence = 1e-12;

// an exact flow's kinetic energy against e^(-4 nu k^2 t) (Taylor-Green) with CVODE at rtol 1e-12: a global
// error a few times the tolerance per unit time (the pendulum's factor near its separatrix is the worst seen,
// here the flow is linear in its one mode) and the energy's relative error twice the state's: 1e-10
inline constexpr double fluid_energy_decay = 1e-10;

// the inviscid, dealiased method of lines conserves energy exactly as a semi-discrete system: what remains is
// CVODE's error at rtol 1e-11 over the shear layer's roll-up start (0.5 s): a global error up to 100 rtol (the
// factor the pendulum near its separatrix shows) and the energy's relative error twice the state's: 2e-9
inline constexpr double inviscid_energy_drift = 2e-9;

// a first-order error halved by halving grid and step together falls by 2: we ask for at least 1.5 (the
// next term is O(h) relative, at CFL 1 up to a third on the coarsest grid)
inline constexpr double first_order_refinement = 1.5;

// a field sent through FFTW's inverse and forward transforms: each is a Cooley-Tukey FFT whose error in the 2-norm
// is at most log2(N) (u + mu) |X| (Higham, Accuracy and Stability of Numerical Algorithms, thm 24.2; mu ~ u for
// FFTW's precomputed twiddles), N = n^2: the pair leaves at most 4 log2(n^2) u |X|_2 on any mode, one that should
// be zero included (1.2e-14 |X| at 48^2), and at most 4 log2(n^2) u max |q| on the mean (the k = 0 mode / n^2)
inline double fft_roundtrip_roundoff(int n) { return 4 * std::log2(static_cast<double>(n) * n) * 0x1p-53; }

// the thin double shear layer (w = 80, L = 1, speed 1) has rolled up into its vortices by t = 1 (Brown & Minion
// 1995, fig. 1: the braids thin from t = 0.8): the inviscid energy check runs to there. Rolled up means the
// cross-flow has grown from the perturbation d = 0.05 to the layers' own speed's order: max |v| at least 5x d
inline constexpr double shear_layer_rollup_time = 1.0;
inline constexpr double rollup_cross_flow_growth = 5.0;

// a back-trace in grid units on a 64^2 grid: coordinates up to n, four roundings each on the way: 8 n u
inline double trace_roundoff(int n) { return 8 * n * 0x1p-53; }

// a quantity summed over the grid's n^2 points (kinetic energy from 2 n^2 squares; enstrophy from n^2, after the
// vorticity's transforms): the recursive sum's relative error at most (2 n^2) u, the transforms' 4 log2(n^2) u
inline double grid_sum_roundoff(int n) { return (2.0 * n * n + 4 * std::log2(static_cast<double>(n) * n)) * 0x1p-53; }

// the trapezoid rule's error over an interval, (dt^3 / 12) max |g''|, with g'' estimated from the run's own
// second differences at the outputs (a sample of it, not its maximum over the interval): a factor 2 for that
inline constexpr double trapezoid_bound_safety = 2.0;

// MacCormack advection is second order where the field is smooth and first order at its extrema (the clamp);
// on the Taylor-Green vortex at CFL 1 its numerical viscosity must fall below bilinear's by at least what one
// refinement of a first-order method buys (first_order_refinement), else it is not worth its second pass
inline constexpr double maccormack_gain = first_order_refinement;

// FFTW's transform against the direct sum of the DFT's definition on an 8^2 grid of values in [-1, 1]: each of
// the 64 terms of a mode rounded once in the sum and once in e^(-i theta) (libm's sin and cos, an ulp): a mode of
// the direct sum errs by ~ sqrt(64) x 2 eps x |values|, FFTW's by log2(64) eps: 1e-13 absolute holds with room
inline constexpr double dft_roundoff = 1e-13;

// kinetic energy at successive outputs of an unforced, viscous run: the semi-discrete energy falls at
// -2 nu x enstrophy, each output's energy summed from n^2 values (~ n eps relative): a rise beyond 1e-12 relative
// is the method's, not the sum's
inline constexpr double energy_sum_roundoff = 1e-12;

// Semi-Lagrangian advection is not conservative: a step changes the density's total by the interpolation's
// error summed over the grid, bilinear's at most (d^2 / 8)(max |rho_xx| + max |rho_yy|) a point, the second
// differences taken on the grid; the midpoint trace of a divergence-free flow moves area only at O(h^3) (left out).
// Summed over the steps, the total's drift must stay within this multiple of that sum (the bound is a worst
// case: errors of both signs cancel in the sum)
inline constexpr double semi_lagrangian_mass_bound = 1.0;

// errors measured against a reference run of CVODE BDF at rtol 1e-12 (not an exact solution): below this
// the reference's own error (a small multiple of its tolerance) is part of what is measured
inline constexpr double reference_floor = 1e-10;

// an IMEX split's two parts against f: each entry of f is the same few terms (a few spring forces, the
// wind's share, drag and gravity; or the Laplacian and the damping) grouped otherwise, so they differ by a
// few roundings of the terms' size: 16 eps of the larger part's magnitude
inline constexpr double split_roundoff = 16 * 2.220446049250313e-16;

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

// one formula written twice, as text (a PDE scene) and by hand (a built-in model), with its operations in another
// order: an evaluation of f differs by a few ulps of its largest term (the 5-point Laplacian's five terms and its
// coefficient rounded once more: 16), so a step's state by that times dt |f|; on a neutrally stable system such
// differences add up at most linearly, a rate's over the steps and a position's once more over the run's t_end
inline constexpr double rewritten_formula_ulps = 16.0;
inline double rewritten_formula_difference(long steps, double dt, double t_end, double largest_rate, double largest_state) {
  return rewritten_formula_ulps * 0x1p-52 * (static_cast<double>(steps) * dt * largest_rate * std::max(1.0, t_end) + largest_state);
}

// the CVODE/GSL cross-check: two adaptive codes at rtol agree to within this multiple of rtol times the
// solution's size; the global error of a tolerance-proportional code on a non-stiff problem of unit
// Lipschitz constant over unit time is a small multiple of rtol (CVODE's guide: "a factor of 10 or so")
inline constexpr double adaptive_agreement_factor = 100.0;

// analytic Jacobian against central differences with d = eps^(1/3) |y|: truncation O(d^2 |f'''|) plus
// round-off O(eps |f| / d), each ~1e-11 for O(1) derivatives; relative to 1 + |J|
inline constexpr double jacobian_fd = 1e-9;

// exact solution against the ODE: its time derivative by a central difference with h = 1e-5 has truncation
// h^2 |y'''| / 6 ~ 1e-10 |y'''| and round-off eps |y| / h ~ 1e-11 |y|; relative to 1 + |f|
inline constexpr double exact_derivative_fd_step = 1e-5;
inline constexpr double exact_ode_residual = 1e-7;

// invariants of exact solutions evaluated through GSL's special functions (accurate to a few ulps)
inline constexpr double exact_invariant = 1e-12;

// a Jacobian only steers an implicit stepper's iteration: replacing it by central differences changes the
// result by no more than the iteration tolerance (GSL's default 1e-6 relative at the control's error level)
inline constexpr double jacobian_steering = 1e-6;

// energy drift of explicit and implicit Euler against the linearised prediction (1 + (w h)^2)^(+-n): at
// theta0 = 0.5 the pendulum's frequency differs from w by theta0^2/16 ~ 1.6% (3% in (w h)^2), and the
// quadratic term of the compounding adds a few percent more over the run
inline constexpr double linearised_drift_band = 0.1;

// Richardson estimate (y_h - y_h/2) 2^p / (2^p - 1) against the true error: off by the next order's share,
// O(h) relative, a few percent at h = T/80 for RK4
inline constexpr double richardson_band = 0.2;

// event times: an adaptive code at rtol 1e-10 puts the ball within ~rtol of its path, and CVODE locates the
// root to ~100 ulps of t; over 27 bounces the errors of successive impacts add
inline constexpr double event_time_adaptive = 1e-8;

// re-stepping to the root of g with a method exact on the parabola (rk4) leaves round-off in t
inline constexpr double event_time_restep = 1e-12;

// a handful of floating-point operations on O(1-10) quantities (a collision response, an apex height from
// closed forms): a few hundred ulps of 1
inline constexpr double kernel_roundoff = 1e-12;

// the first impact of the bouncing ball found by any method at dt = 1e-4 or rtol 1e-10: the segment method
// errs by g h^2 / (8 v) ~ 3e-9 for rk4, explicit Euler's own error by ~h / 2 = 5e-5; 1e-3 s is a frame at
// 1000 fps, far above both and far below a flight (0.7 s)
inline constexpr double first_impact_any_method = 1e-3;

// the ball's rest time across methods: each impact time carries the method's error, and the rest follows
// the last rebound slower than rest_speed, which a method may reach one bounce early or late — a flight of
// 2 rest_speed / g ~ 2 ms, plus the accumulated impact errors; 0.05 s bounds both for dt = 1e-4
inline constexpr double rest_time_any_method = 0.05;

// energy held by rk4 (exact on parabolas) with re-stepped impacts over thousands of events: each impact
// adds round-off of the state, ~eps relative, so the total stays below 1e-9 relative for <= 1e5 events
inline constexpr double event_energy_roundoff = 1e-9;

// per-axis energy after a few impacts of a re-stepped rk4 run, against E0 eps^(2n): each impact time is
// exact to ~eps t, each reflection to a few ulps
inline constexpr double per_impact_energy = 1e-10;

// a sum of m pair forces in another order (cell list against all pairs): each partial sum rounds by eps
// relative to the largest force, so m eps |f|max bounds the difference; with m <= 64 neighbours, 1e-13
// relative to the largest acceleration
inline constexpr double reordered_pair_sum = 1e-13;

// energy of a particle system without drag through an adaptive code at rtol 1e-9 over 1 s: the global error
// of a tolerance-proportional code is a small multiple of rtol times the Lipschitz constant times the run
// (see adaptive_agreement_factor); the repulsion's force has a kink at r_c, which costs CVODE short steps,
// not accuracy (measured: 3e-9 relative at rtol 1e-9, 1.4e-7 at 1e-8). 1e-6 relative leaves room and
// fails at once if a pair force were one-sided (no energy to conserve)
inline constexpr double particle_energy_adaptive = 1e-6;

// energy of the particle system between samples 10 rk4 steps apart (h = 1e-3): drag only removes energy,
// and rk4's local energy error per step is O((w h)^5) of it, w ~ sqrt(2 s) ~ 28 rad/s for the repulsion's
// springs: (0.028)^5 / 120 ~ 1.5e-10 per step, and the force's kink at r_c costs a few orders there;
// 1e-9 of E0 over ten steps. A one-sided pair force or a sign error in the drag would add energy at once
inline constexpr double rk4_energy_per_sample = 1e-9;

// rk4 on the damped oscillators of the particle system (w = 2 rad/s, h = 5e-3, 0.2 s): global error
// ~ (w h)^4 w t / 120 times the amplitude (~3 m) ~ 1e-10 (measured 2.0e-10); 1e-8 leaves room for the
// constant and still fails if `error` compared against the wrong time or state
inline constexpr double rk4_oscillator_error = 1e-8;

// symplectic Euler's energy error stays in a band of width O(h) around the true energy over long runs,
// with no drift: the error over the run's second half exceeds that over its first half by no more than this
// factor (a drifting method, explicit Euler, grows it by orders of magnitude)
inline constexpr double symplectic_band_growth = 1.5;

// how far a particle may lie behind a surface it met: moved onto the face by p - d n, it is on it to a few
// ulps of its coordinates; resting on a tilted face, round-off (or an adaptive code's error) moves it and
// the contact test of particle_mesh.cpp holds it within 1e-7 m. Measured: 3e-15 (rk4) to 8e-12 (cvode-bdf)
inline constexpr double contact_band = 1e-7;

// energy rise between samples of particles raining on a mesh (E0 ~ 700 J/kg for 30 particles): impacts
// only take energy, but a particle sliding off a face's edge sees its acceleration jump by up to g, and the
// step across the jump errs in energy by O(h g |v|) ~ 1e-3 * 10 * 1 = 1e-2 J/kg, 1.4e-5 of E0. Measured:
// rk4 8e-10, gsl-rkf45 1.3e-9, cvode-bdf 6e-12, symplectic Euler 0; a reflection that added energy (eps > 1
// by 0.1) would add ~0.1 J/kg per impact, 1e-4 of E0
inline constexpr double edge_crossing_energy = 1e-5;

// height field: the seeds' scheme against the exact evolution of its modes (one mode in closed form, or
// every mode of a random state through FFTW's DST-I), relative to the field's largest value. The
// figure; round-off alone gives a few ulps per cell per step, which add up at worst linearly (a slowly
// decaying real root keeps every step's error): 4 eps K ~ 4e-13 for K = 1000, and as a random walk
// (rotating complex roots) ~ 4 eps sqrt(K) when K = 3000; the DST round trip adds ~ eps log N. Measured:
// 1.5e-14 (mu = 0), 2.3e-13 (mu = 0.5), 5e-13 (3000 steps, all modes)
inline constexpr double wave_modal = 1e-12;

// a mode's frequency estimated from its amplitudes by least squares, cos(theta) = sum a_k (a_{k+1} + a_{k-1}) /
// (2 sum a_k^2), against the discrete dispersion relation: the data is exact to round-off, so the estimate is
// within ~eps / sin(theta) of theta; 1e-9 relative allows theta as small as 1e-6 while a Laplacian off by one
// ulp in lambda would still show at 1e-16, so this checks the relation, not the digits
inline constexpr double wave_dispersion = 1e-9;

// FFTW's DST-I there and back: ~ eps log2 N per transform; 1e-14 for N = 48
inline constexpr double dst_round_trip = 1e-14;

// the damped scheme's energy against that of the exactly evolved modes after 300 steps (mu = 2, 3.8 s):
// both fields agree to wave_modal of the initial field, which has decayed by e^{-mu t/2} ~ 0.02, so relatively
// 5e-11, and energy is quadratic in the field: ~ 1e-10; 1e-9
inline constexpr double wave_energy_modal = 1e-9;

// the shallow water equations' departure from the wave equation for a drop of height A over depth H:
// D(A) = a A + b A^2 + ..., so D(10 A) / (10 D(A)) = 1 + 9 (b / a) A + ...; with b / a = k / H, k of order
// one (the mass flux eta u and the advection u du/dx are each A / H relative to the linear terms), the
// pair at A/H = 1e-3 and 1e-2 may differ from tenfold by 9 k 1e-3: 5% allows k up to 5. Measured:
// tenfold to 1.5e-4, k = 0.017
inline constexpr double shallow_water_first_order = 0.05;

// the shallow water equations without damping conserve E = (1/2) int (g eta^2 + h |u|^2) dA; the C grid's
// central differences (the advection in advective form) break it at second order in the spacing, so the
// energy change over a run falls fourfold each time the spacing halves (rk4's part, O(dt^4), is far below).
// The ratio of two halvings' changes is 4 (1 + O(d^2)): measured 4.13 (48 -> 95 points) and 4.03 (95 -> 189);
// 3.5 allows the next term 12%. A wrong non-linear term (advection doubled) changes the equations, so the
// change tends to a non-zero limit: measured ratio 2.35 there
inline constexpr double shallow_water_energy_second_order = 3.5;

// the seeds' wave scheme in float32 (GPU shader against the CPU loop, or either against the exact modes):
// a step rounds 7 times per cell (3 adds of the neighbour sum, 3 products, 2 adds, less the one exact
// copy), each by at most u = 2^-24 of S M, S = |self| + |previous| + 4 |neighbours| and M = max |z|: a
// new error of at most delta = 7 u S M per cell, sqrt(cells) delta in the 2-norm. The scheme carries an
// error in a mode of angle theta (roots e^{+-i theta}, undamped) as sin((k+1) theta) / sin theta <=
// min(k + 1, 1 / sin theta), so after k steps the 2-norm error is at most
// k min(k + 1, 1 / sin theta_min) sqrt(cells) delta (damping only shrinks it): a bound, not an estimate
inline constexpr double float32_wave_roundings = 7;
inline constexpr double float32_unit_roundoff = 0x1p-24;
// k steps of a new error of at most delta per cell, carried as above: k min(k + 1, 1 / sin theta_min)
// sqrt(cells) delta
inline double carried_roundoff(long steps, double sin_theta_min, double cells, double delta) {
  const double growth = std::min(static_cast<double>(steps) + 1, 1 / sin_theta_min);
  return static_cast<double>(steps) * growth * std::sqrt(cells) * delta;
}
inline double float32_wave_bound(long steps, double sin_theta_min, double coefficient_sum, double max_abs_z, double cells) {
  return carried_roundoff(steps, sin_theta_min, cells, float32_wave_roundings * float32_unit_roundoff * coefficient_sum * max_abs_z);
}

// gpu-vbd-compute's converged step against backward Euler's (Newton on the same G to round-off). Its sweeps stop where
// each node's gradient, as float32 computes it, moves the node by less than the line search can tell: where
// |g_i| is within a few roundings of S_i, the sum of the magnitudes of the gradient's terms (the inertia's m / h^2 |e_i|,
// D0's |D0_ij| |e_j| / h, |f0_i|, and each spring's c (|L - l| + |r| + |x_i| + |x_j|): its length formed from float32
// positions, then L - l cancelled). A node's terms are at most 3 + 12 springs, each some 8 roundings from float32 inputs,
// summed with one more each: 32 roundings bound them. G's Hessian is at least M / h^2, so x - x* = H^-1 (g - 0) is at
// most h^2 / m_min |g|_2 (m)
inline constexpr double vbd_float32_roundings = 32;
inline double vbd_float32_step(double h, double least_mass, double gradient_scale) {
  return h * h / least_mass * vbd_float32_roundings * float32_unit_roundoff * gradient_scale;
}

// the second seed's symplectic Euler in float32 (GPU pass against the CPU loop): eliminating v, its z obeys
// the three-level recurrence above (undamped), fed each step by the rounding of z1 = z + h v1 (2
// roundings of at most u (Z + h V)) and h times that of v1 = v + h c2 (sum - 4 z) (6 of at most
// u (V + 8 h c2 Z)), Z = max |z|, V = max |v|: delta = u (2 (Z + h V) + 6 h (V + 8 h c2 Z)) per cell,
// carried as there
inline double float32_symplectic_wave_bound(long steps, double sin_theta_min, double h, double c2, double max_abs_z, double max_abs_v, double cells) {
  const double delta = float32_unit_roundoff * (2 * (max_abs_z + h * max_abs_v) + 6 * h * (max_abs_v + 8 * h * c2 * max_abs_z));
  return carried_roundoff(steps, sin_theta_min, cells, delta);
}

// the cloth's symplectic Euler step node by node (solvers/cloth_grid.hpp; gpu-cloth's pass), in a precision of
// unit round-off u, against the same step in exact arithmetic (or a conforming GPU's reordering of it).
// Per free node and step the roundings are: at most 40 in the acceleration (a spring's force takes 18: the
// span, its dot product and square root, the unit vector, the elongation, the closing speed's dot product,
// the products and sums of (c e + gamma de/dt) u; then up to 18 sums of the node's terms and 4 for the mass,
// drag and gravity), each at most u times the acceleration's scale
//   A = (12 c_max (L_max + l_max) + 12 gamma 2 V + 6 k_w (|w| + V) L_max^2 / 2 + |pick|) / m + drag V + g
// (every term's magnitude bounded: springs at most L_max long, velocities at most V), which reach x through
// h^2; 2 in v1 = v + h a (at most u (V + h A) each, reaching x through h) and 2 in x1 = x + h v1
// (u (X + h V)). One step from the same state therefore differs by at most
//   delta = u (2 (X + h V) + 2 h (V + h A) + 40 h^2 A) per node, sqrt(nodes) delta in the positions' 2-norm.
inline constexpr double cloth_acceleration_roundings = 40;
inline constexpr double float64_unit_roundoff = 0x1p-53;
struct ClothRoundoffScale {
  double max_x = 0, max_v = 0;  // X, V: the largest |x| and |v| component over the run (m, m/s)
  double acceleration = 0;      // A above (m/s^2)
};
inline double cloth_step_roundoff(double unit, double h, double nodes, const ClothRoundoffScale& s) {
  return unit * (2 * (s.max_x + h * s.max_v) + 2 * h * (s.max_v + h * s.acceleration) + cloth_acceleration_roundings * h * h * s.acceleration) *
         std::sqrt(nodes);
}

// vbd_float32_step in float64: two float64 sweeps of one G that round differently (vbd's layout of a network of springs and
// G's own view of each node) each stop within it of G's minimiser, and a sweep carries a difference on without
// amplifying it (a Gauss-Seidel sweep of G contracts in G's Hessian norm). Where the gradient holds a stiff spring's
// c |r| (the compliant rod's 1e6 N/m over 1 m) against a node's mass term m / h^2, this is far above eps |x|
inline double vbd_float64_step(double h, double least_mass, double gradient_scale) {
  return h * h / least_mass * vbd_float32_roundings * float64_unit_roundoff * gradient_scale;
}

// k steps: each step's new error carried by symplectic Euler's linearised propagator, whose powers map a
// position error by at most 1 / cos(theta / 2) (theta a mode's angle; <= 1 / cos(pi / 4) for h omega <= sqrt 2)
// and a velocity error into x by at most k h: with the step's errors split so (the x roundings and the rest),
// at most k sqrt 2 d_x + k (k + 1) / 2 (d - d_x); d_x = 2 u (X + h V) sqrt(nodes), d = cloth_step_roundoff. A
// linearised bound, for h omega <= sqrt 2 (the tests run at half the limit, h omega = 1): it holds while the
// motion stays near-linear over the k steps (a buckling sheet can amplify errors faster), which the tests'
// horizons keep
inline double cloth_steps_bound(double unit, long steps, double h, double nodes, const ClothRoundoffScale& s) {
  const double k = static_cast<double>(steps), d = cloth_step_roundoff(unit, h, nodes, s), d_x = 2 * unit * (s.max_x + h * s.max_v) * std::sqrt(nodes);
  return k * std::sqrt(2.0) * d_x + k * (k + 1) / 2 * (d - d_x);
}

// CVODE's method of lines on a mode of frequency w over t: a tolerance-proportional code's global error is
// rtol times the solution's size times a factor that grows with the Lipschitz constant over the interval
// (CVODE's guide: "a factor of 10 or so" per unit; here w t ~ 24): at most 1e3 rtol |y|. Measured at
// rtol 1e-10: Adams 9 rtol |y|, BDF 250 rtol |y|
inline constexpr double method_of_lines_rtol_multiple = 1e3;

// the stability limit found by bisection (to 1e-3) against the derivation: the 1% asked
inline constexpr double stability_match = 0.01;
inline constexpr double stability_bisection_width = 1e-3;
// spectrum_stable_dt bisects its step to 1e-9 of the bracket's top, which lies within a factor 2 of the limit
inline constexpr double spectrum_limit_bisection = 2e-9;

// the scheme's energy E^{k+1/2} at mu = 0 is conserved exactly in exact arithmetic; each step's rounding
// (~ eps per cell, random-walked over K = 10^4 steps) moves it by ~ eps sqrt(K) ~ 2e-14 of E
inline constexpr double wave_energy_roundoff = 1e-12;

// polyhedral mass properties: sums over at most ~1000 faces of cubic and quartic products of the
// coordinates, each a few ulps; 1000 faces x 4 ulps x a factor 20 for the shift to the centre of mass
inline constexpr double mass_properties_roundoff = 1e-12;

// the torque-free angular velocity: rk8pd at dt = 0.01 on rates <= 1 rad/s truncates by ~1e-18 per
// step, so what is left is round-off over 2e4 steps (~1e-12, measured 1.6e-12) and GSL's elliptic
// functions (~1e-15): 1e-10 leaves a factor 60
inline constexpr double elliptic_closed_form = 1e-10;

// the flip period from zero crossings interpolated linearly between steps of 1e-3 s: the chord's error at
// a crossing is h^2 |w''| / (8 |w'|) ~ 1e-7 s for |w''| ~ |w'| ~ 1, and the methods' own phase errors
// (rk4: ~1e-12; the splitting, order 2: ~(w h)^2 t / 24 ~ 1e-7 s over 60 s): 1e-5 relative of a 20 s
// period holds both with a factor 100
inline constexpr double flip_period = 1e-5;

// rk4 at dt = 1e-3 against the projectile with drag: truncation (k dt)^4 ~ 1e-14 of the motion, round-off
// 2000 steps x a few ulps of |x| ~ 5 m: ~1e-12 m; 1e-10 m leaves a factor 100
inline constexpr double falling_body = 1e-10;

// a projection's correction is of the order of the local error, so an adaptive method's step count with
// it may differ from the count without only as much as a perturbation of that size moves the controller:
// within a factor 1.5 (a restart after every projection, the fault this guards against, costs x500)
inline constexpr double projection_step_ratio = 1.5;

// Contacts (models/contact.hpp).
// contact geometry of bodies ~0.5 m across: depths, points and normals through a rotation and a plane
// distance or an overlap along an axis, each a few ulps of the coordinates (~1e-16 m): 1e-12 m or
// 1e-12 of a unit normal leaves a factor 1000
inline constexpr double contact_geometry_roundoff = 1e-12;
// A body released touching the ground falls one step of gravity, g dt^2, before its contacts (found at the
// step's start, penetration strictly positive) hold it: that much settling, and 1e-6 of it for round-off
inline constexpr double resting_settle(double g, double dt) { return g * dt * dt * (1 + 1e-6); }
// then Gauss-Seidel leaves at most contact_velocity_tolerance at each contact: it creeps by at most that
// speed times the time it rests (the bound asked over 10 s: 1e-9 m), and its kinetic energy is at most
// that of the speed, m v^2 / 2, with a factor 10 for rotation's share
inline constexpr double resting_creep(double seconds) { return contact_velocity_tolerance * seconds; }
inline constexpr double resting_kinetic(double mass) { return 10 * mass * contact_velocity_tolerance * contact_velocity_tolerance / 2; }
// a kinetic energy rise below this fraction is round-off of the sums (the impulses' own guard uses it):
// a few ulps for each of ~100 contacts' terms
inline constexpr double impulse_energy_roundoff = contact_energy_roundoff;
// momentum over impulses: each is applied to two bodies as +j and -j at one point, so momentum is kept to
// the rounding of the sums, a few ulps per impulse over ~1e5 impulses of a run: 1e-11 of the momentum
inline constexpr double impulse_momentum_roundoff = 1e-11;
// a box sliding down a slope steeper than its friction angle: symplectic Euler's velocity is exact for a
// constant acceleration, so only round-off remains, ulps over 1000 steps
inline constexpr double sliding_roundoff = 1e-12;

// A hanging chain settling: Voigt damping gamma along the springs damps a mode of frequency w at the rate
// gamma w^2 / (2 c) (damping ratio gamma w / (2 c)); the slowest is the lowest mode, w1 = 2 sqrt(c/m)
// sin(pi / (2 (2N + 1))) for N masses hanging from a pin. A start A0 away from the equilibrium has at most
// 2 A0 exp(-gamma w1^2 t / (2 c)) left at t (the factor 2 for the mode's shape at the bottom node);
// implicit Euler damps faster still. Measured for the scene: CVODE BDF's decay 0.23/s against 0.224/s.
inline double chain_settled(double t, double start_offset, int nodes, double mass, double stiffness, double damping) {
  const double w1 = 2 * std::sqrt(stiffness / mass) * std::sin(3.141592653589793 / (2 * (2 * nodes + 1)));
  return 2 * start_offset * std::exp(-damping * w1 * w1 * t / (2 * stiffness));
}
// an analytic Jacobian against central differences Richardson-extrapolated from steps h and h/2: the
// truncation falls to O(h^4 |f^(5)|) ~ 1e-24 * 1e9 and what is left is round-off, eps |f| / h ~ 2e-16 * 1e2 /
// 1e-6 ~ 2e-8 absolute, ~1e-11 of |J| ~ 1e3: 1e-9 relative to 1 + |J| holds it with a factor 100
inline constexpr double richardson_step = 1e-6;
inline constexpr double jacobian_richardson = 1e-9;
// a position or velocity that should vanish, computed from O(1) quantities over a run of ~1e4 steps:
// round-off accumulated as a random walk of ulps, ~1e-14; 1e-12 leaves a factor 100
inline constexpr double accumulated_roundoff = 1e-12;
// internal spring forces are equal and opposite along the spring: their sum and their moment vanish to the
// rounding of the sums, a few ulps of the largest force per spring
inline constexpr double spring_momentum_roundoff = 1e-13;

// ---- cloth

// the same configuration seen through a symmetry of the grid (a sheet transposed): each node's force sums its
// twelve springs' k (|d| - L) d / |d|, a few roundings each on coordinates and lengths of order one, in another
// order: the two agree to ~12 x 8 eps ~ 2e-14 of the largest force; 1e-12 leaves a factor 50
inline constexpr double spring_force_roundoff = 1e-12;

// implicit Euler's amplification on the undamped oscillator, 1 / sqrt(1 + w^2 h^2) in the energy norm
// (w x, v), is exact for a linear spring: one step's ratio against it is round-off, a few eps over the
// few operations of the solve
inline constexpr double implicit_damping_roundoff = 1e-12;

// a measured stability limit against the prediction from the stiffest mode: the probe (2000 steps stay
// within 1e6) sees growth only once |R|^2000 > 1e6, i.e. |R| - 1 > 0.7%; where |R| climbs past 1 steeply
// (symplectic Euler: at h w = 2 its two roots meet at -1 and split) that is a step 0.1-1% past the
// boundary, which stability_match (1%) allows; rk4's damped boundary is crossed at a shallow angle, and the
// same 0.7% of |R| is a step up to 10% past it (measured 4-9% over 3 decades of stiffness)
inline constexpr double rk4_probe_excess = 0.10;

// cloth-on-sphere: a node put back onto the sphere's surface lies on it to the rounding of c + r n, and the
// next step's motion inward is undone at the step's end; after the step nothing is inside by more than eps r
inline constexpr double obstacle_roundoff = 1e-12;

// ---- the continuum cloth's elements (test_membrane.cpp)
// an element's force against central differences of its energy (and df/dx against differences of the force)
// with a step d = eps^(1/3) of the element's size L: truncation d^2 |W's third derivative| / 6 ~ eps^(2/3) |f|
// and round-off eps |W| / d ~ eps^(2/3) |f| (W ~ |f| L), each ~4e-11 of the largest entry for strains of
// order 0.1; 1e-7 of it leaves a factor 1000 for the strain's higher powers, where a dropped factor 1/2 or a
// wrong sign is an error of order one
inline constexpr double element_fd = 1e-7;
// sums of a few dozen products of O(1) numbers (a node's forces from its six elements and a dozen bending
// stencils, a 9 x 9 eigendecomposition): round-off, some hundred eps of the largest term
inline constexpr double element_roundoff = 1e-12;
// a strip stretched by 0.1%: St. Venant-Kirchhoff on the Green strain E = e + e^2 / 2 departs from linear
// elasticity's Poisson's ratio and modulus at first order in the strain (a few e: ~0.3%); 1% (the one asked
// figure) leaves a factor 3, where a wrong Lame parameter (plane strain's lambda for plane stress's) is off by
// tens of percent at nu = 0.3
inline constexpr double small_strain_elastic_constants = 0.01;
// the plate's bending energy on a cylinder against D / (2 R^2): second differences of the wrapped grid are its
// curvature to O((h / R)^2) (2.4e-4 at h = 1/32, R = 2); 1e-3 leaves a factor 4, where a missing (1 - nu) or a cell's
// twist counted once instead of twice is off by tens of percent. A quadratic placement (the saddle) is exact to round-off
inline constexpr double cylinder_bending = 1e-3;
// a clamped plate's tip deflection against Kirchhoff's plate strip, q L^4 / (8 D), extrapolated from 17 and 33 nodes along
// the span at the measured first order: what Richardson leaves is the next order's term, 0.4% at nu = 0 where the
// strip's answer is exact (the (9, 17) and (17, 33) extrapolations differ by 1.4%, a quarter of that at second order);
// and four spans along the clamped edge leave the curl of the free side edges (anticlastic bending, softening toward the
// beam's E t^3 / 12, 11% at nu = 0.33) under 1% at the middle (0.8% measured). 2% holds both, where the rigidity without
// its 1 - nu^2 is 11% off
inline constexpr double plate_strip_bending = 0.02;
// the incremental potential G of a step (solvers/incremental_potential.hpp) evaluated two ways, node by node (vbd's
// view) and whole: a sum of some 10^4 terms (elements, springs, the inertia) each rounded to eps of itself, at most
// n eps |G| apart (1.3e-12 |G| at n = 6000, the 32^2 continuum's terms); 1e-11 leaves a factor 8, where a node's
// inertia without its h^2 (3600 times too stiff at 1/60 s) is off by orders of magnitude
inline constexpr double potential_roundoff = 1e-11;
// Newton's observed order from three successive residuals: 2 for quadratic convergence, up to the variation of
// its error constant between iterations; 1 for a linearly converging (modified) iteration. 1.5 tells them apart
inline constexpr double newton_order_floor = 1.5;
// a symplectic method's energy error stays in a band of width O(h) for exponentially long times (Hairer, Lubich
// & Wanner, ch. IX): the band's maximum is met within its first oscillations, and a later window's maximum is
// within twice the first's, where a non-symplectic method's drift grows without bound
inline constexpr double symplectic_energy_band_growth = 2.0;

}  // namespace stepwise::tolerance

namespace stepwise::tolerance {

// ---- rendering and caustics

// the photon map of still water is E0 cos(theta) T at every texel: the shader forms each triangle's area and
// its projection from differences of float coordinates of size `spacing` on a square of `side`, each off by
// up to 2 eps_f side / spacing relative, four of them in the ratio and the refraction step's rounding: 16
// eps_f side / spacing bounds the relative error
inline double still_photon_map(double side, double spacing) { return 16 * 0x1p-23 * side / spacing; }

// total flux on the floor against sum A cos(theta) T over the surface triangles: rasterising at texel
// centres misplaces at most the texels the union's outline crosses, perimeter 4 side over texel side / M,
// each carrying at most the texel's area times the irradiance: 4 / M relative
inline double photon_flux(int resolution) { return 4.0 / resolution; }

// a sinusoidal surface h = A sin(kx) over depth D against the small-slope (paraxial) intensity: the slope
// approximations (sin, tan and cos of angles ~ A k) drop terms of relative size (A k)^2, the ray's start at
// z = h instead of 0 one of A / D times the focusing D (1 - 1/n) A k^2, and the grid's central-difference
// normals and linear triangles one of (k d)^2 times the focusing; bounded by the sum, a factor 4 on each.
// A triangle's flat irradiance is its mean, met somewhere inside it, so a texel centre within a grid step d
// of that point reads it off by up to |d ln I / dx| d (log_slope: the largest |d ln I / dx|)
inline double paraxial_caustic(double A, double k, double D, double d, double focusing, double log_slope) {
  return 4 * ((A * k) * (A * k) + (A / D + (k * d) * (k * d)) * focusing) + log_slope * d;
}

// the GPU photon map against the CPU photon tracer, bin by bin in units of the tracer's standard error:
// over ~1000 bins a Gaussian exceeds 4.5 sigma with probability 7e-6 each, 0.7% for the largest; the mean
// of z^2 over the bins is 1 +- sqrt(2 / bins) ~ 0.04, and a bias in the map would push it up: within 1.3
inline constexpr double photon_trace_max_z = 4.5;
inline constexpr double photon_trace_mean_z2 = 1.3;

// a ball's pixel centroid against the projection of its centre: the pixel grid quantises the disc's
// centroid by at most half a pixel, and perspective moves the centroid of a sphere's image off the
// projected centre by (r / distance)^2 times the centre's offset from the image's middle
inline double ball_centroid_px(double radius, double distance, double offset_px) {
  return 0.5 + (radius / distance) * (radius / distance) * offset_px;
}

// the box of a frame's drawn pixels against the box its geometry projects to, side by side. A pixel is drawn
// when its centre is covered, so nothing is drawn more than a pixel beyond the projected side. Inward, a
// side made by a sharp corner of interior angle a is first drawn where the corner is wide enough to hold
// a pixel centre wherever it lies: where its inscribed circle reaches radius sqrt(2)/2, at (sqrt(2)/2) /
// sin(a/2) from its tip; plus the pixel, 1 + 0.707/sin(a/2) = 3 px for corners down to a = 36 degrees
// (sheets seen at a grazing angle, a cloth's drooping corner)
inline constexpr double silhouette_px = 1.0;
inline constexpr double silhouette_tip_px = 3.0;

// the pixels a flat sheet covers against its projected area: at most the pixels its outline crosses, one
// per pixel of outline length, and the rest exact
inline double coverage_px(double outline_px) { return outline_px; }

// a field's colour at a node's pixel against its value's place on the colour map: 8-bit rounding of the map's
// mix and of the GL's (a level each), plus what the linear texture changes over the half pixel by which the
// pixel's centre may miss the node (the colour's change a pixel, measured across the image)
inline double field_colour_levels(double levels_per_pixel) { return 2 + 0.5 * levels_per_pixel; }

// implicit-euler's kept-factor solves (mass_spring_implicit.hpp) stop at a relative residual of 1e-8, and whether
// a step reuses the factor or refactorises is decided from the CPU time each took: two runs of a cloth (serial
// or under mpirun alike) agree to what that residual allows, not to the bit (measured: 1e-11 relative over the
// quick report's cloth tables). The ranks test (mpi_ranks.py reads this line) asks the residual itself.
inline constexpr double kept_factor_reproducibility = 1e-8;
// the same, for an offset in pixels between two runs of such a cloth (cloth_solvers' pixels_off, continuum-cloth's
// pixels_vs_converged): a difference of positions, so its round-off is the positions' and not the offset's. Each
// step's solve leaves at most the residual (1e-8) of a position within the 720-pixel frame, and a damped implicit
// step carries the earlier steps' errors without growing them: over the quick report's longest cloth run (60 steps:
// 0.25 s at 1/240 s), 1e-8 x 720 x 60 = 4.32e-4 pixels (measured: 9e-6 under 3 ranks)
inline constexpr double kept_factor_pixel_offset = 4.32e-4;

// two solvers of one backward Euler step on the constraints study's compliant rod (vbd's sweeps, xpbd's iterations,
// implicit-euler-newton), each converged: apart by at most Newton's velocity tolerance (1e-5 m/s a step,
// solvers/incremental_potential.hpp) times the run's 2 s, in the bob's position (m). report/check_report.py reads this
inline constexpr double compliant_rod_converged = 2e-5;

// the equations model against a hand-written twin (the built-in pendulum, a hand-coded f): the same formula with
// its operations in another order or grouping (g/L once, or g times 1/L each call) differs by a few ulps a call,
// 4 eps |f| bounding it; over a run of N steps those differences add, at most linearly on a non-chaotic orbit:
// 1e4 steps x 4 eps ~ 1e-11 of |y| (1e-10 holds it, where a wrong formula or sign is off by O(dt) or more)
inline constexpr double formula_roundoff = 4 * 2.220446049250313e-16;
inline constexpr double equations_run_roundoff = 1e-10;

// the Rosenbrock methods' dense output between steps: a continuous extension of order >= 3 over steps h ~ 0.01 s
// (rodas4 at rtol 1e-7 on a 3 rad/s oscillator: 383 steps in 5 s) errs by ~ h^4 |y^(4)| / 24 ~ 1e-8 inside a
// step, the global error's size; 10 rtol |y| bounds it, where a wrong coefficient leaves an O(h |y'|) ~ 1e-2 error
inline constexpr double dense_output_rtols = 10;

// two panels of a side-by-side video showing the same picture, decoded: H.264 at CRF 20 leaves ~40 dB PSNR (an
// RMS error of ~2.5 of 255 levels), but its ringing at a hard edge (a rod, a silhouette) reaches ~50 levels at
// isolated pixels (measured up to 56 where the pictures were the same, in 2e-5 of a panel's pixels). Two
// decoded panels are the same picture where at most 1e-4 of their pixels are over 48 levels apart; a shape
// moved by a pixel or more moves its edge, hundreds of pixels over that (measured 4e-3 of the panel for the
// pendulum 4 px off, 0.49 for the water diverged)
inline constexpr double video_noise_levels = 48;
inline constexpr double video_noise_share = 1e-4;

// position-based dynamics (solvers/methods/position_based.cpp). One projection of a distance constraint with
// alpha = 0 moves the point by -C along the unit direction: |p - C n| = |p| - C to the rounding of the norm, the
// division and the update, a few eps of the length (4 eps |x|). XPBD's hanging mass at its static stretch
// m g alpha is a fixed point of every substep and iteration (dlambda = 0 there): each substep's rounding moves it
// by at most 4 eps of the length, adding at most linearly over the substeps (the step is contractive). PBD's
// fixed point differs by a fraction of the stretch (its per-iteration stiffness): over a tenth of it is a
// different law, not rounding
inline constexpr double projection_roundoff = 4 * 2.220446049250313e-16;
inline constexpr double pbd_stretch_differs = 0.1;
// RATTLE's SHAKE stops when each constraint is off by at most 8 eps of (its length + twice its ends' largest
// coordinate), the rounding of the coordinates it is computed from (solvers/methods/rattle.cpp): the pendulum's
// rod is then within 8 eps (L + 2 L)
inline constexpr double shake_converged = 8 * 2.220446049250313e-16;
// Baumgarte's critically damped pull at w returns a drift within ~1/w: over a run of T the drift it leaves is
// ~1/(w T) of the unstabilised one's (the chain: w = 140/s, T = 1 s, 1/140); a tenth leaves room for the
// constant, where a sign error in the pull makes the drift grow instead
inline constexpr double baumgarte_drift_share = 0.1;
// a chain's links after RATTLE's SHAKE: each met to the rounding of coordinates of about the chain's length over
// the link's (20 links: 20 x 8 eps ~ 4e-14 of a link), and the next step's drift moves them by the rounding of
// its own update: 1e-12 of a link holds a second of steps, where an unconverged solve leaves 1e-6 or more
inline constexpr double chain_link_roundoff = 1e-12;
// IDA (the DAE) and CVODE's BDF (the ODE form) are the same variable-order BDF with the same local error control:
// at the same tolerances their global errors are alike (measured: IDA's 0.02-0.95 of CVODE's on the Cartesian
// pendulum and the chain at rtol 1e-6 and 1e-9); twice CVODE's leaves room, where a wrong multiplier or a
// residual sign leaves errors of the motion's own size
inline constexpr double bdf_peer_factor = 2.0;

}  // namespace stepwise::tolerance

namespace stepwise::tolerance {

// ---- events in a scene's own equations (test_equation_events.cpp)
// an impact time's error is the height's error over the impact speed: a tolerance-proportional global error of
// a few rtol x h0 (1 m), over the slowest impact's speed (rest_speed / e = 0.0125 m/s), is a few hundred rtol;
// 1000 rtol bounds it (measured: 1e-12 to 2e-11 at rtol 1e-10 for the one-step codes, 4.6e-8 for GSL's msbdf)
inline constexpr double event_time_per_rtol = 1e3;
// a fixed-step method of order >= 2 steps the ball's parabola exactly, and its events are located to round-off
// on it (measured: 9e-15 for rk4 at dt 1e-3): a few hundred ulps of the 4 s run
inline constexpr double event_time_exact_steps = 1e-12;
// a root refined to round-off in the step's fraction s (1e-15) of a step h: where the event's time is exact
inline double event_time_located(double h) { return 1e-13 + 1e-14 * h; }
// uniform motion (x' = v constant) is stepped exactly by every method, to round-off; each event of it is located to
// SUNDIALS' root tolerance, 100 eps (|t| + |h|) with the step h at most t, the widest of the methods' (the
// hand-written pass: 1e-15 of the step); an event's time carries the location errors of the up to t + 1 events
// before it (test_event_actions.cpp: the ball between two walls)
inline double event_time_linear_motion(double t) { return 200 * std::numeric_limits<double>::epsilon() * (1 + t) * (1 + t); }

// Newton on the incremental potential with its exact Hessian near the minimiser: the error e_{k+1} <= C e_k^2, so the
// steps' sizes contract at order 2 (log(m_{k+1} / m_k) / log(m_k / m_{k-1}) -> 2); 1.5 leaves room for the constant C
// over the last few steps, and fails a Newton with a wrong Hessian (linear: order 1, as the projected one's 0.88 an
// iteration on the flag's first step)
inline constexpr double newton_quadratic_order = 1.5;
// two Newton solutions of one backward Euler step, each stopped where its last step (or the error Newton's contraction
// predicts after it) moved no node faster than the velocity tolerance v: each within about v h of the minimiser (the
// exact one's error after its last step is that step's square, the inexact one's the forcing term times it, <= 0.1),
// so within 2 v h of each other
inline constexpr double newton_stopping_gap = 2;

// linear triangles (membrane) and the vertex-form bending on them converge at order 1 in the mesh size at least in a
// displacement; 0.8 leaves room for the pre-asymptotic meshes and fails a refinement that does not converge (the
// two-point sheet's sag, order 0.45)
inline constexpr double fem_refinement_order = 0.8;

// the continuum's damping force against its velocity Jacobian times v: one linear map evaluated two ways (element by
// element, then summed), each sum's round-off a few eps of the largest element force (at most |f| times the ~6
// elements at a node over the cancellation): 1e-12 of 1 + |f|, where a wrong term is O(|f|)
inline constexpr double damping_linear_map = 1e-12;

// a run's cpu_seconds on 2 threads against the same run's on 1 (the same sweeps, statically split): every thread's
// CPU time counted, the two agree but for the team's start and join (measured 1.0-1.2); the calling thread's alone
// would be half the work (~0.5). 0.75 lies between
inline constexpr double worker_cpu_share = 0.75;

// Chebyshev's acceleration of vbd's sweeps at their measured rate rho gains at least this share, in logarithm, of the
// gain theory gives an iteration of that rate (rho^k against 2 r^k / (1 + r^2k)): the sweeps are nonlinear, and Gauss-
// Seidel's spectrum is not the real interval the weights assume. Measured on the 16^2 flag's step after 10, 20 and 40
// sweeps: 0.63-0.87 of it (springs and continuum); the weights computed for rho^2 instead (an error of the recurrence
// or of the rate given) reach 0.35-0.43
inline constexpr double chebyshev_gain_share = 0.5;

}  // namespace stepwise::tolerance
