// The incompressible fluid's checks shared by the suite and the report: the viscosity a Taylor-Green run's decay
// implies (how much of Stable Fluids' look is its own diffusion), and the explicit methods' step limits on the
// pseudo-spectral method of lines, closed-form and from the Jacobian's spectrum.
#pragma once

#include <stepwise/models/model.hpp>

#include <memory>
#include <optional>
#include <string_view>

namespace stepwise {

// The Taylor-Green vortex these checks and the report's fluid section use: L = 1 m, mode 1 (k = 2 pi), A = 1 m/s
std::unique_ptr<Model> unit_taylor_green(int n, double nu);

// The viscosity the Taylor-Green vortex's energy decay implies between y0 (t = 0) and y (t):
// E(t) = E(0) e^(-4 nu k^2 t), k = 2 pi m / L
double taylor_green_effective_viscosity(const Model& model, double k, const Eigen::VectorXd& y0, const Eigen::VectorXd& y, double t);

// A Taylor-Green vortex (L = 1 m, mode 1, A = 1 m/s) on n x n points with viscosity nu, run by `method` at the
// fixed step h to t_end: the effective viscosity its decay implies (NaN where the run did not finish). With
// bilinear semi-Lagrangian advection a step moves the field by a fraction s of a cell and interpolation smooths it
// by d^2 s (1 - s) / 2 per step: an added viscosity ~ d |u| s (1 - s) / (2 CFL) per unit time, first order in d
// at a fixed CFL number A h / d
double taylor_green_viscosity(std::string_view method, int n, double nu, double h, double t_end);

// The closed-form step limits of an explicit method with a stability function R (verification/stability.hpp) on
// the de-aliased spectral discretisation of n x n points on a square of side L, frozen coefficients at the highest
// mode kept, |kx| = |ky| = kmax = (2 pi / L) floor((n - 1) / 3): advection alone gives it the eigenvalue
// i (u kx + v ky), at most i s kmax with s = max (|u| + |v|) over the grid (h below R's reach up the imaginary axis
// over it: none for explicit Euler), viscosity alone -nu 2 kmax^2 (R's reach along the negative real axis over it),
// and both together -nu 2 kmax^2 + i s kmax. Empty without R.
struct FluidStepLimits {
  double advective = 0, viscous = 0, combined = 0;
};
std::optional<FluidStepLimits> fluid_step_limits(std::string_view method, int n, double length, double speed_sum, double nu);

// The largest step `method` survives on the Taylor-Green vortex (L = 1 m, mode 1, A = 1 m/s) on n x n points with
// viscosity nu, measured by bisection (to tolerance::stability_bisection_width) from a tenth of `predicted` to
// the first of 10, 40, 160 ... times it that fails: `steps` steps from the vortex with every grid value perturbed by up to 1e-3 m/s (seeded; the exact
// vortex has nothing in its high modes for an instability to grow from but round-off) stay within 1e6 of the start.
// The Galerkin truncation conserves energy or loses it, so a bounded run is bounded whatever the flow does.
double taylor_green_measured_stable_dt(std::string_view method, int n, double nu, long steps, double predicted);

}  // namespace stepwise
