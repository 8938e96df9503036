// Stability limits found where the methods fail: bisection on the step between a run that stays bounded
// and one that does not, and the limits theory predicts for the height field.
#pragma once

#include <stepwise/models/model.hpp>
#include <stepwise/solvers/method_table.hpp>
#include <stepwise/solvers/stability.hpp>

#include <complex>
#include <tuple>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

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
  static auto fields(auto& s) { return std::tie(s.measured, s.derived, s.seeds); }
};
WaveStability wave_stability(std::string_view method, int points, double spacing, double c, double mu, long steps);

// The largest step each explicit method survives on that mode, the linear oscillator x'' = -omega^2 x - 2 a x'
// with eigenvalues lambda = -a +- i sqrt(omega^2 - a^2): symplectic Euler h < 2 (sqrt(a^2 + omega^2) - a) /
// omega^2 (h omega < 2 undamped; the damping, explicit, shrinks it), rk4 where |R(h lambda)| reaches 1 (h omega =
// 2 sqrt 2 undamped: its stability region's reach up the imaginary axis), explicit Euler |1 + h lambda| <= 1,
// so h < 2 a / omega^2: none at all without damping. Empty for any other method.
std::optional<double> mass_spring_stable_dt(std::string_view method, const StiffestMode& mode);

// One explicit method's largest stable step on a mass-spring model, measured by bisection (to
// tolerance::stability_bisection_width) between a tenth and ten times the predicted limit (or 1e-6 s and 1 s
// where none is predicted): `steps` steps from the model's initial state stay within 1e6 of its size.
double measured_stable_dt(const Model& model, std::string_view method, long steps, double predicted);

// The stability function R(z) of a one-step method on y' = lambda y, z = h lambda: explicit Euler 1 + z, rk4
// 1 + z + z^2/2 + z^3/6 + z^4/24, implicit Euler 1 / (1 - z). Empty for a method without one (symplectic Euler
// is a map on (x, v) pairs, not a function of z alone; multistep and adaptive methods).
std::optional<std::complex<double>> stability_function(std::string_view method, std::complex<double> z);

// R(z) of a one-step method, measured where the method table gives none: one fixed step of h = 1 on
// y' = [[a, -b], [b, a]] y from y = (1, 0), the complex scalar equation y' = z y with z = a + ib written in real
// pairs, lands on (Re R(z), Im R(z)) for any Runge-Kutta method (its step is a rational function of h A applied to
// y0), to the tolerance of an implicit method's linear solve. For the fixed-step methods that take a plain system
// and have one documented order (multistep and extrapolation codes choose theirs: no R); empty otherwise
std::optional<std::function<std::complex<double>(std::complex<double>)>> measured_stability_function(const Method& method);

// the largest stable step of `method` on `eigenvalues`: from its R(z) where the method table has it, else from
// the measured one; empty where it has neither
std::optional<double> predicted_stable_dt(const Method& method, const Eigen::VectorXcd& eigenvalues);

// The eigenvalues of the system's Jacobian df/dy at (t, y) (its own Jacobian, else central differences), dense:
// for systems of a few hundred unknowns
Eigen::VectorXcd jacobian_spectrum(const OdeSystem& system, double t, const Eigen::VectorXd& y);

// The eigenvalues that bound a step and say a stiffness: all of them (jacobian_spectrum) for a system of up to
// dense_spectrum_size unknowns, else the leading_eigenvalues of largest magnitude by restarted Arnoldi (Spectra's
// GenEigsSolver on the system's sparse Jacobian, or the dense one), at a cost of matrix-vector products rather
// than the n^3 of the whole spectrum (minutes at the flag's 6 000 unknowns)
inline constexpr int dense_spectrum_size = 600, leading_eigenvalues = 24;
Eigen::VectorXcd leading_spectrum(const OdeSystem& system, double t, const Eigen::VectorXd& y);

// The largest h with |R(h lambda)| <= 1 for every eigenvalue: h is raised by factors of 2 from 1e-3 / max |lambda|
// until some |R| exceeds 1 + 1e-9, then bisected to 1e-9. Positive real parts below 1e-6 of the largest |lambda|
// are taken as 0 and smaller eigenvalues left out (a difference Jacobian resolves no finer). 0 where even the
// first h grows (explicit Euler on an undamped spectrum), infinity where no h up to 1e6 / min |lambda| grows
// (implicit Euler), empty without R(z).
std::optional<double> spectrum_stable_dt(std::string_view method, const Eigen::VectorXcd& eigenvalues);

// The sheet the cloth's stability checks use (the test and the report's table): 8 x 8 nodes, 0.5 kg, hanging
// from its two top corners, no wind, shear and bend springs at 1/2 and 1/10 of the structural stiffness c.
std::unique_ptr<Model> stability_sheet(double stiffness);

// Implicit Euler's numerical damping: one mass on one undamped spring moving along it (a linear oscillator
// about its equilibrium, w = 20 rad/s), `steps` steps of h = wh / w by `implicit-euler`; the amplitude
// sqrt(w^2 u^2 + v^2) each step keeps, to compare with 1 / sqrt(1 + w^2 h^2)
std::vector<double> implicit_euler_amplitude_ratios(double wh, int steps);

}  // namespace stepwise
