// The incompressible fluid: the pseudo-spectral method of lines against the exact Navier-Stokes flows
// (Taylor-Green, the shear wave), its divergence and its invariants; Stam's Stable Fluids, stable at any step
// and diffusive by an amount that falls as grid and step are refined.
#include "models/model.hpp"
#include "run/measure.hpp"
#include "run/scene.hpp"
#include "solvers/periodic_fft.hpp"
#include "solvers/semi_lagrangian.hpp"
#include "solvers/capabilities/imex_split.hpp"
#include "verification/fluid_checks.hpp"
#include "verification/order_fit.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace stepwise {
namespace {

constexpr double two_pi = 2 * std::numbers::pi;

// max |grad u| over the four derivatives on the grid, spectral (the divergence is the model's summary's)
double largest_gradient(const Eigen::VectorXd& y, int n, double length) {
  const PeriodicFft fft(n, length);
  const int M = fft.modes(), P = n * n;
  std::vector<PeriodicFft::Complex> U(M), V(M), tmp(M);
  fft.forward(y.data(), U.data());
  fft.forward(y.data() + P, V.data());
  std::vector<double> g(P);
  double grad = 0;
  for (const auto* a : {&U, &V})
    for (const bool along_x : {true, false}) {
      for (int m = 0; m < M; ++m) tmp[m] = along_x ? fft.d_dx(m, (*a)[m]) : fft.d_dy(m, (*a)[m]);
      fft.inverse(tmp.data(), g.data());
      for (const double x : g) grad = std::max(grad, std::abs(x));
    }
  return grad;
}

// one of the model's summary quantities, by name
double summary_value(const Model& model, const Eigen::VectorXd& y, std::string_view name) {
  const auto names = model.summary_names();
  return model.summary(y)[std::find(names.begin(), names.end(), name) - names.begin()];
}

// max |div u| / max |grad u|
double relative_divergence(const Model& model, const Eigen::VectorXd& y, int n) {
  return summary_value(model, y, "max_divergence") / largest_gradient(y, n, 1.0);
}

// the whole state at every output (a large model's runs keep only its summary otherwise)
StepControl whole(StepControl c) {
  c.observe = [](const Eigen::VectorXd& y) { return y; };
  return c;
}

TEST(Fluid, TheMethodOfLinesKeepsTheVelocityDivergenceFreeAtEveryOutput) {
  for (const char* flow : {"taylor-green", "shear-layer", "smoke"}) {
    const auto model = make_model(flow, {{"size", 64}});
    const Measured m = run_and_measure(*model, "rk4", whole(StepControl::fixed(5e-3)), 0.5, 0.05);
    ASSERT_EQ(m.result.status, Status::ok) << flow << ": " << m.result.message;
    double worst = 0;
    for (const auto& y : m.result.trajectory.y) worst = std::max(worst, relative_divergence(*model, y, 64));
    std::cout << flow << ": max |div u| / max |grad u| over the outputs " << worst << '\n';
    EXPECT_LE(worst, tolerance::spectral_divergence) << flow;
  }
}

// kinetic energy against the exact decay, relative, at every output
double worst_energy_error(const Model& model, const Measured& m) {
  double worst = 0;
  for (size_t k = 0; k < m.result.trajectory.t.size(); ++k) {
    const double exact = *model.energy(model.exact(m.result.trajectory.t[k]));
    worst = std::max(worst, std::abs(*model.energy(m.result.trajectory.y[k]) / exact - 1));
  }
  return worst;
}

TEST(Fluid, TheExactFlowsEnergyDecayIsFollowedToCvodesTolerance) {
  for (const char* flow : {"taylor-green", "shear-wave"}) {
    const auto model = make_model(flow, {{"size", 32}, {"mode", 2}, {"viscosity", 0.01}});
    const Measured m = run_and_measure(*model, "cvode-adams", whole(StepControl::adaptive(1e-12, 1e-14)), 1.0, 0.1);
    ASSERT_EQ(m.result.status, Status::ok) << flow << ": " << m.result.message;
    const double worst = worst_energy_error(*model, m);
    std::cout << flow << " with cvode-adams at rtol 1e-12: energy's relative error " << worst << ", state's " << *m.error << '\n';
    EXPECT_LE(worst, tolerance::fluid_energy_decay) << flow;
  }
}

TEST(Fluid, Rk4ConvergesAtItsFourthOrderOnTheTaylorGreenVortex) {
  // the vortex decays at lambda = 2 nu k^2 = 15.8/s (nu = 0.05, m = 2), h lambda 0.32 down to 0.02 over the
  // halvings; the grid's fastest kept mode (wavenumbers (5, 5) on 16^2) decays at 98.7/s, inside rk4's
  // stability limit h lambda <= 2.78 for h <= 0.028
  const auto model = make_model("taylor-green", {{"size", 16}, {"mode", 2}, {"viscosity", 0.05}});
  std::vector<double> steps, errors;
  for (double h = 0.02; h > 0.001; h /= 2) {
    const Measured m = run_and_measure(*model, "rk4", whole(StepControl::fixed(h)), 0.2, 0.2);
    ASSERT_EQ(m.result.status, Status::ok);
    if (*m.error < tolerance::roundoff_floor) break;
    steps.push_back(h);
    errors.push_back(*m.error);
  }
  ASSERT_GE(steps.size(), 4u);
  const double order = loglog_slope(steps, errors);
  std::cout << "rk4 on Taylor-Green: order " << order << " over " << steps.size() << " steps from " << errors.front() << '\n';
  EXPECT_NEAR(order, 4.0, tolerance::order_band);
}

TEST(Fluid, WithoutViscosityTheDealiasedMethodOfLinesConservesEnergyAndDensity) {
  // the 2/3-rule pseudo-spectral form is the Galerkin truncation, which conserves kinetic energy exactly
  // when nu = 0; the density's mean is its k = 0 mode, which advection by a divergence-free flow never moves
  const auto model = make_model("shear-layer", {{"size", 64}, {"viscosity", 0.0}});
  const Measured m = run_and_measure(*model, "cvode-adams", whole(StepControl::adaptive(1e-11, 1e-13)), 0.5, 0.5);
  ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
  const double e0 = *model->energy(model->initial_state()), e1 = *model->energy(m.result.trajectory.y.back());
  std::cout << "shear layer, nu = 0: energy changed by " << e1 / e0 - 1 << " (relative) in 0.5 s\n";
  EXPECT_LE(std::abs(e1 / e0 - 1), tolerance::inviscid_energy_drift);
  // the smoke's density total grows at the source's integral, rate 2 pi r^2 for a Gaussian of unit peak
  const double r = 0.04, t = 1.0;
  const auto smoke = make_model("smoke", {{"size", 64}, {"source_radius", r}, {"source_rate", 1.0}});
  const Measured s = run_and_measure(*smoke, "rk4", whole(StepControl::fixed(5e-3)), t, t);
  ASSERT_EQ(s.result.status, Status::ok);
  const double total = summary_value(*smoke, s.result.trajectory.y.back(), "density_total");
  std::cout << "smoke: density total " << total << " after " << t << " s, the source's " << two_pi * r * r * t << '\n';
  EXPECT_NEAR(total / (two_pi * r * r * t), 1.0, tolerance::spectral_divergence);
}

TEST(Fluid, TheDealiasedRightHandSideHasNoModePastTheTwoThirdsRuleOnEitherAxis) {
  // f of a state with every mode filled (random values on the grid, not band-limited): each of u', v' and rho'
  // is dealiased before it returns to the grid, so its transform has nothing, to the round-off of the two
  // transforms between, at a mode with |kx| or |ky| past K = floor((n - 1) / 3) (either axis alone)
  const int n = 48;
  const auto model = make_model("smoke", {{"size", n}});
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd y(model->size());
  for (auto& x : y) x = u(rng);
  Eigen::VectorXd f(y.size());
  model->rhs(0, y, f);
  const PeriodicFft fft(n, 1.0);
  std::vector<PeriodicFft::Complex> modes(fft.modes());
  for (int q = 0; q < 3; ++q) {
    fft.forward(f.data() + q * n * n, modes.data());
    // the wavenumbers from the layout itself (row r is r or r - n, column c is c), not from the rule under test
    const int half = n / 2 + 1, K = PeriodicFft::largest_kept(n);
    double dropped = 0, total = 0;
    int dropped_x = 0, dropped_y = 0;
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < half; ++c) {
        const PeriodicFft::Complex a = modes[r * half + c];
        total += std::norm(a);
        const bool past_x = c > K, past_y = std::abs(r <= n / 2 ? r : r - n) > K;
        if (!past_x && !past_y) continue;
        dropped = std::max(dropped, std::abs(a));
        dropped_x += past_x && !past_y;
        dropped_y += past_y && !past_x;
      }
    ASSERT_GT(dropped_x, 0);
    ASSERT_GT(dropped_y, 0);
    const double bound = tolerance::fft_roundtrip_roundoff(n) * std::sqrt(total);
    std::cout << "f's field " << q << " on " << n << "^2: largest mode past the 2/3 rule " << dropped << " (bound " << bound << ", |f^| " << std::sqrt(total)
              << ")\n";
    EXPECT_LE(dropped, bound) << "field " << q;
  }
}

TEST(Fluid, WithoutViscosityTheEnergyIsConservedThroughTheShearLayersRollUp) {
  // the inviscid Galerkin truncation conserves energy however far the flow cascades: run the thin layer
  // (w = 80) through its roll-up, where the spectrum fills out to the cut-off and aliasing left on one axis
  // would feed energy in or out
  for (const int n : {48, 64}) {
    const auto model = make_model("shear-layer", {{"size", n}, {"viscosity", 0.0}, {"width", 80}});
    const double t = tolerance::shear_layer_rollup_time;
    const Measured m = run_and_measure(*model, "cvode-adams", whole(StepControl::adaptive(1e-11, 1e-13)), t, t);
    ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
    const double e0 = *model->energy(model->initial_state()), e1 = *model->energy(m.result.trajectory.y.back());
    const auto cross_flow = [&](const Eigen::VectorXd& y) { return y.segment(n * n, n * n).lpNorm<Eigen::Infinity>(); };
    const double v0 = cross_flow(model->initial_state()), v1 = cross_flow(m.result.trajectory.y.back());
    std::cout << "thin shear layer, nu = 0, " << n << "^2: energy changed by " << e1 / e0 - 1 << " (relative) in " << t << " s; max |v| " << v0 << " -> " << v1
              << '\n';
    EXPECT_GT(v1, tolerance::rollup_cross_flow_growth * v0) << "the layer has rolled up";
    EXPECT_LE(std::abs(e1 / e0 - 1), tolerance::inviscid_energy_drift);
  }
}

TEST(Fluid, TheBackTraceFollowsTheExactCharacteristicsOfAShearAndARotation) {
  // the trace alone (semi_lagrangian.hpp), in grid units on a 64^2 grid, on linear flows, where bilinear
  // sampling of the velocity is exact away from the periodic seam (only points whose trace stays 3 cells inside
  // it are compared):
  //  - a shear u = gamma (y - c), v = 0: x_back = x - s gamma (y - c), y_back = y, what the midpoint rule gives
  //    exactly (the flow's second derivative along the path is zero): round-off
  //  - a solid-body rotation about the centre, u = -omega (y - c), v = omega (x - c): the exact trace turns
  //    (x, y) about c by -omega h; the midpoint rule's error is (omega h)^3 / 6 |r|, third order in h
  const int n = 64;
  const double c = n / 2.0;
  std::vector<double> u(n * n), v(n * n), bx(n * n), by(n * n);
  const auto inside = [&](int k) {
    const double i = k / n, j = k % n;
    return std::min({i, j, bx[k], by[k]}) > 3 && std::max({i, j, bx[k], by[k]}) < n - 4;
  };
  const double gamma = 0.4, s = 2.0;
  for (int k = 0; k < n * n; ++k) u[k] = gamma * (k / n - c), v[k] = 0;
  semi_lagrangian::trace(u.data(), v.data(), n, s, bx.data(), by.data());
  double shear_error = 0;
  int compared = 0;
  for (int k = 0; k < n * n; ++k) {
    if (!inside(k)) continue;
    const double i = k / n, j = k % n;
    shear_error = std::max({shear_error, std::abs(bx[k] - (j - s * gamma * (i - c))), std::abs(by[k] - i)});
    ++compared;
  }
  std::cout << "back-trace on a shear: largest error " << shear_error << " cells over " << compared << " points\n";
  ASSERT_GT(compared, n * n / 4);
  EXPECT_LE(shear_error, tolerance::trace_roundoff(n));

  const double omega = 0.5;
  for (int k = 0; k < n * n; ++k) u[k] = -omega * (k / n - c), v[k] = omega * (k % n - c);
  std::vector<double> steps, errors;
  for (double h = 0.4; h > 0.02; h /= 2) {
    semi_lagrangian::trace(u.data(), v.data(), n, h, bx.data(), by.data());
    const Eigen::Rotation2Dd back(-omega * h);
    double worst = 0;
    for (int k = 0; k < n * n; ++k) {
      if (!inside(k)) continue;
      const Eigen::Vector2d exact = Eigen::Vector2d(c, c) + back * Eigen::Vector2d(k % n - c, k / n - c);
      worst = std::max(worst, (Eigen::Vector2d(bx[k], by[k]) - exact).norm());
    }
    steps.push_back(h);
    errors.push_back(worst);
  }
  const double order = loglog_slope(steps, errors);
  std::cout << "back-trace on a rotation: error " << errors.front() << " -> " << errors.back() << " cells, local order " << order << '\n';
  EXPECT_NEAR(order, 3.0, tolerance::order_band);
}

TEST(Fluid, TheDiagnosticsAreTheTaylorGreenVortexsClosedForms) {
  // u = A sin(kx) cos(ky), v = -A cos(kx) sin(ky) on [0, L)^2: kinetic energy (1/2) int |u|^2 = A^2 L^2 / 4,
  // vorticity w = 2 A k sin(kx) sin(ky), enstrophy (1/2) int w^2 = A^2 k^2 L^2 / 2, their ratio 2 k^2; the grid's
  // sums of these trigonometric products are the integrals exactly (discrete orthogonality), so only round-off is
  // left; and at t both decay as e^(-4 nu k^2 t) (the velocity as e^(-2 nu k^2 t))
  const double A = 0.7, L = 2.0, nu = 0.01, t = 0.5;
  const int n = 32, mode = 2;
  const double k = 2 * std::numbers::pi * mode / L;
  const auto model = make_model("taylor-green", {{"size", n}, {"length", L}, {"mode", mode}, {"amplitude", A}, {"viscosity", nu}});
  for (const double at : {0.0, t}) {
    const Eigen::VectorXd y = model->exact(at);
    const double decay = std::exp(-4 * nu * k * k * at);
    const double energy = summary_value(*model, y, "kinetic_energy"), enstrophy = summary_value(*model, y, "enstrophy");
    std::cout << "Taylor-Green at t = " << at << ": kinetic energy " << energy << " (closed form " << A * A * L * L / 4 * decay << "), enstrophy " << enstrophy
              << " (" << A * A * k * k * L * L / 2 * decay << "), ratio / 2k^2 " << enstrophy / energy / (2 * k * k) << '\n';
    EXPECT_NEAR(energy / (A * A * L * L / 4 * decay), 1, tolerance::grid_sum_roundoff(n));
    EXPECT_NEAR(enstrophy / (A * A * k * k * L * L / 2 * decay), 1, tolerance::grid_sum_roundoff(n));
    EXPECT_NEAR(enstrophy / energy / (2 * k * k), 1, tolerance::grid_sum_roundoff(n));
    EXPECT_NEAR(summary_value(*model, y, "max_divergence"), 0, tolerance::spectral_divergence * 2 * A * k);
  }
}

TEST(Fluid, TheEnergyFallsAtTwiceTheViscosityTimesTheEnstrophyInTheRunsOwnNumbers) {
  // dE/dt = -2 nu Z for the unforced semi-discrete system (advection and projection do no work): between two
  // outputs dt apart, E(t + dt) - E(t) = -nu dt (Z(t) + Z(t + dt)) with the trapezoid rule's error, at most
  // (dt^3 / 12) 2 nu max |Z''|, Z'' estimated from the run's own second differences; the shear layer rolling up
  const double nu = 2e-3, dt = 0.01;
  const auto model = make_model("shear-layer", {{"size", 32}, {"viscosity", nu}});
  StepControl control = StepControl::fixed(1e-3);
  control.observe = [&](const Eigen::VectorXd& y) { return model->summary(y); };
  const Measured m = run_and_measure(*model, "rk4", control, 1.0, dt);
  ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
  const auto names = model->summary_names();
  const auto column = [&](std::string_view name) {
    const size_t c = std::find(names.begin(), names.end(), name) - names.begin();
    std::vector<double> out;
    for (const auto& s : m.result.trajectory.y) out.push_back(s[static_cast<Eigen::Index>(c)]);
    return out;
  };
  const std::vector<double> E = column("kinetic_energy"), Z = column("enstrophy");
  ASSERT_GE(E.size(), 50u);
  double z2 = 0, worst = 0, dissipated = 0;
  for (size_t i = 1; i + 1 < Z.size(); ++i) z2 = std::max(z2, std::abs(Z[i + 1] - 2 * Z[i] + Z[i - 1]) / (dt * dt));
  for (size_t i = 0; i + 1 < E.size(); ++i) {
    const double trapezoid = -nu * dt * (Z[i] + Z[i + 1]);
    worst = std::max(worst, std::abs(E[i + 1] - E[i] - trapezoid));
    dissipated = std::max(dissipated, std::abs(trapezoid));
  }
  const double bound = tolerance::trapezoid_bound_safety * dt * dt * dt / 12 * 2 * nu * z2;
  std::cout << "shear layer, nu = " << nu << ": |dE - (-2 nu Z dt)| at most " << worst << " a step of " << dt << " s, the trapezoid's bound " << bound
            << ", the dissipation " << dissipated << '\n';
  EXPECT_LE(worst, bound);
  EXPECT_GT(dissipated, 10 * bound) << "the balance is not within the bound by being small";
}

// bilinear interpolation's error bound integrated over the square, for a field q (n x n, spacing d): each point's
// (d^2 / 8)(|q_xx| + |q_yy|) from its second differences, times its area d^2
double interpolation_error_integral(const double* q, int n, double d) {
  double sum = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double c = q[i * n + j];
      const double xx = std::abs(q[i * n + (j + 1) % n] - 2 * c + q[i * n + (j + n - 1) % n]);
      const double yy = std::abs(q[((i + 1) % n) * n + j] - 2 * c + q[((i + n - 1) % n) * n + j]);
      sum += d * d / 8 * (xx + yy);
    }
  return sum;
}

// the mean of field q (0 u, 1 v) over the grid
double mean_velocity(const Eigen::VectorXd& y, int n, int q) { return y.segment(static_cast<Eigen::Index>(q) * n * n, n * n).mean(); }

TEST(Fluid, TheSmokesMeanVelocityStaysZeroAndStableFluidsConvergesToTheMethodOfLines) {
  // buoyancy lifts the density above its mean and pushes the rest down (Boussinesq about the mean), so the flow's
  // mean momentum, its k = 0 mode, which the projection and the advection keep, stays zero to round-off: in
  // both the method of lines and Stable Fluids, at every output. A lift from the whole density would move the
  // smoke up as one at b x (mean density)
  // Stable Fluids' advection interpolates, which moves a field's mean by at most bilinear's error integrated over
  // the square (as the density total's test below), a step: its bound is that, summed over the steps
  const double t = 1.0;
  for (const auto& [method, h] : {std::pair{"rk4", 5e-3}, {"stable-fluids", 1.0 / 32}}) {
    const int n = 64;
    const auto smoke = make_model("smoke", {{"size", n}});
    const Measured m = run_and_measure(*smoke, method, whole(StepControl::fixed(h)), t, h);
    ASSERT_EQ(m.result.status, Status::ok) << method;
    double worst = 0, largest = 0, interpolation = 0;
    for (const auto& y : m.result.trajectory.y) {
      worst = std::max({worst, std::abs(mean_velocity(y, n, 0)), std::abs(mean_velocity(y, n, 1))});
      largest = std::max(largest, y.head(2 * n * n).lpNorm<Eigen::Infinity>());
      interpolation += std::max(interpolation_error_integral(y.data(), n, 1.0 / n), interpolation_error_integral(y.data() + n * n, n, 1.0 / n));
    }
    const double roundoff = tolerance::fft_roundtrip_roundoff(n) * (t / h) * 4 * largest;
    const double bound = method == std::string("rk4") ? roundoff : roundoff + tolerance::semi_lagrangian_mass_bound * interpolation;
    std::cout << method << " on the smoke: largest mean velocity " << worst << " m/s over " << t << " s (bound " << bound << ", largest |u| " << largest
              << ")\n";
    EXPECT_GT(largest, 0) << method << ": the smoke rises";
    EXPECT_LE(worst, bound) << method;
  }
  // Stable Fluids against the method of lines on the same grid (rk4 at a hundredth of its step: the reference),
  // grid and step refined together at a fixed advective CFL: the velocities' difference falls at first order
  double previous = 0;
  for (const int n : {32, 64, 128}) {
    const auto smoke = make_model("smoke", {{"size", n}});
    const double h = 1.0 / n, t_end = 0.25;
    const Measured reference = run_and_measure(*smoke, "rk4", whole(StepControl::fixed(h / 8)), t_end, t_end);
    const Measured stam = run_and_measure(*smoke, "stable-fluids", whole(StepControl::fixed(h)), t_end, t_end);
    ASSERT_EQ(reference.result.status, Status::ok);
    ASSERT_EQ(stam.result.status, Status::ok);
    const Eigen::VectorXd a = reference.result.trajectory.y.back().head(2 * n * n), b = stam.result.trajectory.y.back().head(2 * n * n);
    const double gap = (a - b).norm() / a.norm();
    std::cout << "smoke at " << t_end << " s on " << n << "^2, h = " << h << ": stable-fluids against the method of lines, relative gap " << gap << '\n';
    if (previous > 0) {
      EXPECT_LT(gap, previous / tolerance::first_order_refinement) << n;
    }
    previous = gap;
  }
}

// The double shear layer has no exact solution; its reference is a converged run, in both senses:
//  - in space, the scene's own flow (scenes/shear-layer.toml, rolled up to its t_end) on finer and finer grids:
//    a Fourier method on an analytic flow converges faster than any power of 1/n, so the enstrophy's change
//    from one grid to the next falls by more than a fourth-order method's would (the differences of C n^-4);
//  - in time, the work-precision study's reference (gsl-rk8pd at rtol 1e-13 on 24^2 over 0.25 s) against an
//    independent code at the same tolerance, CVODE's Adams: two adaptive codes agree to a small multiple of rtol.
TEST(Fluid, TheShearLayersReferenceIsConvergedInSpaceAndInTime) {
  const Scene scene = load_scene(scenes_directory() + "/shear-layer.toml");
  ASSERT_TRUE(scene.t_end && scene.dt);
  const std::vector<int> grids{64, 96, 128};
  std::vector<double> enstrophy;
  for (const int n : grids) {
    Params p = scene.parameters;
    p["size"] = n;
    const auto model = make_model("shear-layer", p);
    const Measured m = run_and_measure(*model, "rk4", whole(StepControl::fixed(*scene.dt)), *scene.t_end, *scene.t_end);
    ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
    enstrophy.push_back(summary_value(*model, m.result.trajectory.y.back(), "enstrophy"));
  }
  const double fall = std::abs(enstrophy[0] - enstrophy[1]) / std::abs(enstrophy[1] - enstrophy[2]);
  const auto power = [&](int i) { return std::pow(grids[i], -4.0); };
  const double fourth_order_fall = (power(0) - power(1)) / (power(1) - power(2));
  std::cout << "shear layer at t = " << *scene.t_end << " s: enstrophy " << enstrophy[0] << ", " << enstrophy[1] << ", " << enstrophy[2]
            << " on 64, 96, 128^2; the change falls " << fall << "x (fourth order: " << fourth_order_fall << "x)\n";
  EXPECT_GT(fall, fourth_order_fall);

  const double rtol = 1e-13, t = 0.25;
  const auto model = make_model("shear-layer", {{"size", 24}});
  const Measured a = run_and_measure(*model, "gsl-rk8pd", StepControl::adaptive(rtol, 1e-3 * rtol), t, t);
  const Measured b = run_and_measure(*model, "cvode-adams", StepControl::adaptive(rtol, 1e-3 * rtol), t, t);
  ASSERT_EQ(a.result.status, Status::ok) << a.result.message;
  ASSERT_EQ(b.result.status, Status::ok) << b.result.message;
  const double size = a.result.y_stop.lpNorm<Eigen::Infinity>(), gap = (a.result.y_stop - b.result.y_stop).lpNorm<Eigen::Infinity>();
  std::cout << "shear layer 24^2 at " << t << " s: gsl-rk8pd and cvode-adams at rtol " << rtol << " differ by " << gap << " (max |y| " << size << ")\n";
  EXPECT_LE(gap, tolerance::adaptive_agreement_factor * rtol * size);
}

// the viscosity the Taylor-Green decay implies (verification/fluid_checks.hpp)
double effective_viscosity(const Model& model, const Measured& m, double k) {
  return taylor_green_effective_viscosity(model, k, model.initial_state(), m.result.trajectory.y.back(), m.result.trajectory.t.back());
}

TEST(Fluid, StableFluidsIsStableAtAnyStepAndItsNumericalViscosityFallsWithGridAndStep) {
  const double nu = 1e-3, t_end = 1.0, k = two_pi;
  double previous = 0;
  for (const int n : {16, 32, 64}) {
    const auto model = make_model("taylor-green", {{"size", n}, {"viscosity", nu}});
    // the step at advective CFL 1 (A h / d = 1): the grid and the step refined together
    const double h = 1.0 / n;
    const Measured m = run_and_measure(*model, "stable-fluids", whole(StepControl::fixed(h)), t_end, t_end);
    ASSERT_EQ(m.result.status, Status::ok);
    const double excess = effective_viscosity(*model, m, k) / nu - 1;
    std::cout << "stable-fluids on " << n << "^2, h = " << h << ": effective viscosity " << excess + 1 << " nu\n";
    EXPECT_GT(excess, 0) << n;  // the method's own diffusion adds to nu
    if (previous > 0) {
      EXPECT_LT(excess, previous / tolerance::first_order_refinement) << n;
    }
    previous = excess;
    EXPECT_LE(relative_divergence(*model, m.result.trajectory.y.back(), n), tolerance::spectral_divergence) << n;
  }
  // far beyond any explicit limit (advective CFL 20): bounded, the energy only falls
  const auto model = make_model("taylor-green", {{"size", 32}, {"viscosity", nu}});
  const Measured m = run_and_measure(*model, "stable-fluids", whole(StepControl::fixed(20.0 / 32)), 10.0, 10.0 / 16);
  ASSERT_EQ(m.result.status, Status::ok);
  double before = *model->energy(model->initial_state());
  for (size_t i = 0; i < m.result.trajectory.y.size(); ++i) {
    const double e = *model->energy(m.result.trajectory.y[i]);
    EXPECT_LE(e, before) << "output " << i;
    before = e;
  }
}

TEST(Fluid, MacCormackAdvectionIsLessDiffusiveThanBilinear) {
  const auto model = make_model("taylor-green", {{"size", 32}, {"viscosity", 1e-3}});
  const double k = two_pi;
  const Measured bilinear = run_and_measure(*model, "stable-fluids", whole(StepControl::fixed(1.0 / 32)), 1.0, 1.0);
  const Measured maccormack = run_and_measure(*model, "stable-fluids-maccormack", whole(StepControl::fixed(1.0 / 32)), 1.0, 1.0);
  const double a = effective_viscosity(*model, bilinear, k), b = effective_viscosity(*model, maccormack, k);
  std::cout << "effective viscosity on 32^2 at CFL 1: bilinear " << a / 1e-3 << " nu, MacCormack " << b / 1e-3 << " nu\n";
  EXPECT_LT(b - 1e-3, (a - 1e-3) / tolerance::maccormack_gain);
}

// FFTW's real-to-complex transform, once, against the DFT's definition summed directly: a^(kx, ky) =
// sum over (x, y) of q e^(-2 pi i (c j + r i) / n)
TEST(Fluid, FftwsTransformIsTheDirectDftToRoundOff) {
  const int n = 8;
  const PeriodicFft fft(n, 1.0);
  std::vector<double> q(n * n);
  for (int k = 0; k < n * n; ++k) q[k] = std::sin(1.7 * k + 0.3) * std::cos(0.37 * k * k);  // in [-1, 1], no pattern
  std::vector<PeriodicFft::Complex> modes(fft.modes());
  fft.forward(q.data(), modes.data());
  double worst = 0;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c <= n / 2; ++c) {
      PeriodicFft::Complex direct = 0;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) direct += q[i * n + j] * std::polar(1.0, -two_pi * (c * j + r * i) / n);
      worst = std::max(worst, std::abs(modes[r * (n / 2 + 1) + c] - direct));
    }
  std::cout << "FFTW against the direct DFT on 8^2: largest difference " << worst << '\n';
  EXPECT_LE(worst, tolerance::dft_roundoff);
  // and back: inverse(forward(q)) = q
  std::vector<double> back(n * n);
  fft.inverse(modes.data(), back.data());
  for (int k = 0; k < n * n; ++k) EXPECT_NEAR(back[k], q[k], tolerance::dft_roundoff) << k;
}

// without forcing, viscosity only takes energy out: the method of lines (dE/dt = -2 nu enstrophy for the
// semi-discrete system) and Stable Fluids (interpolation, implicit diffusion and projection each shrink it) at
// every output, on the shear layer rolling up
TEST(Fluid, WithoutForcingTheEnergyNeverRises) {
  const auto model = make_model("shear-layer", {{"size", 32}, {"viscosity", 1e-3}});
  for (const auto& [method, h] : {std::pair{"rk4", 2e-3}, {"stable-fluids", 1.0 / 32}, {"stable-fluids", 4.0 / 32}}) {
    const Measured m = run_and_measure(*model, method, whole(StepControl::fixed(h)), 1.0, h);
    ASSERT_EQ(m.result.status, Status::ok) << method;
    double before = *model->energy(model->initial_state());
    double largest_rise = -1;
    for (const auto& y : m.result.trajectory.y) {
      const double e = *model->energy(y);
      largest_rise = std::max(largest_rise, e / before - 1);
      before = e;
    }
    std::cout << method << " at h = " << h << ": largest rise of the energy between outputs " << largest_rise << " (relative)\n";
    EXPECT_LE(largest_rise, tolerance::energy_sum_roundoff) << method << " at h = " << h;
  }
}

// the smoke's density total under Stable Fluids: the source adds 2 pi r^2 a second (its grid sum is the integral
// to round-off at r >= 1.3 d), implicit diffusion and projection keep the mean; advection by interpolation moves
// it, by at most the interpolation's error summed over the grid each step (tolerances.hpp), and by an amount that
// falls at first order as grid and step are refined together (an O(d^2) error a step, 1/h = n steps)
TEST(Fluid, StableFluidsDensityTotalStaysWithinTheInterpolationBoundAndConvergesAtFirstOrder) {
  const double r = 0.04, t = 1.0, source = two_pi * r * r * t;
  double previous = 0;
  for (const int n : {32, 64, 128}) {
    const double h = 1.0 / n, d = 1.0 / n;
    const auto smoke = make_model("smoke", {{"size", n}, {"source_radius", r}, {"source_rate", 1.0}});
    const Measured m = run_and_measure(*smoke, "stable-fluids", whole(StepControl::fixed(h)), t, h);
    ASSERT_EQ(m.result.status, Status::ok);
    double bound = 0;
    for (size_t s = 0; s + 1 < m.result.trajectory.y.size(); ++s) bound += interpolation_error_integral(m.result.trajectory.y[s].data() + 2 * n * n, n, d);
    const double drift = std::abs(summary_value(*smoke, m.result.trajectory.y.back(), "density_total") - source);
    std::cout << "stable-fluids smoke on " << n << "^2: the density total drifts by " << drift / source << " of the source's " << source
              << "; the interpolation bound " << bound / source << '\n';
    EXPECT_LE(drift, tolerance::semi_lagrangian_mass_bound * bound) << n;
    if (previous > 0) {
      EXPECT_LT(drift, previous / tolerance::first_order_refinement) << n;
    }
    previous = drift;
  }
}

// the IMEX split: viscosity (and the density's diffusion) implicit, advection, buoyancy and the source explicit.
// Its solve is the inverse of 1 - gamma df_I/dy to round-off; with it ARKODE's IMEX methods run the viscous vortex
// at ten times rk4's viscous limit and converge there at their orders
TEST(Fluid, TheImexSplitsSolveInvertsItsImplicitPartAndItsMethodsKeepTheirOrdersPastTheViscousLimit) {
  const auto smoke = make_model("smoke", {{"size", 16}, {"viscosity", 0.01}, {"diffusivity", 0.02}});
  const ImexSplit* split = smoke->as<ImexSplit>();
  ASSERT_NE(split, nullptr);
  ASSERT_TRUE(split->implicit_solve);
  // x band-limited and divergence-free (a state of the method of lines): b = x - gamma f_I(x), solved back
  Eigen::VectorXd x = smoke->initial_state();
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += 0.1 * std::sin(0.37 * static_cast<double>(i));
  Eigen::VectorXd fi(x.size());
  split->implicit_part(0, x, fi);
  const double gamma = 0.05;
  Eigen::VectorXd b = x - gamma * fi, solved = b;
  split->implicit_solve(gamma, solved);
  Eigen::VectorXd back = solved;  // (1 - gamma J) solved = b
  Eigen::VectorXd fs(x.size());
  split->implicit_part(0, solved, fs);
  back -= gamma * fs;
  std::cout << "IMEX solve: |(1 - gamma J) x - b| / |b| = " << (back - b).lpNorm<Eigen::Infinity>() / b.lpNorm<Eigen::Infinity>() << '\n';
  EXPECT_LE((back - b).lpNorm<Eigen::Infinity>(), tolerance::dft_roundoff * b.lpNorm<Eigen::Infinity>());

  // the vortex at nu = 0.3 on 16^2: rk4's viscous limit 2.785 / (nu 2 kmax^2) = 4.7e-3 s; the IMEX methods from
  // ten times it, against the exact decay
  const auto vortex = make_model("taylor-green", {{"size", 16}, {"viscosity", 0.3}});
  const double rk4_limit = fluid_step_limits("rk4", 16, 1.0, 1.0, 0.3)->viscous;
  for (const auto& [method, order] : {std::pair{"arkode-imex-ark324", 3.0}, {"arkode-imex-ark436", 4.0}, {"arkode-imex-ark548", 5.0}}) {
    std::vector<double> steps, errors;
    for (double h = 10 * rk4_limit; h > rk4_limit / 8; h /= 2) {
      const Measured m = run_and_measure(*vortex, method, whole(StepControl::fixed(h)), 0.1, 0.1);
      ASSERT_EQ(m.result.status, Status::ok) << method << " at h = " << h << ": " << m.result.message;
      if (*m.error < tolerance::roundoff_floor) break;
      steps.push_back(h);
      errors.push_back(*m.error);
    }
    ASSERT_GE(steps.size(), 5u) << method;
    // at 10x the limit the vortex's own mode has h lambda ~ 1 (its decay rate 2 nu k^2 = 24/s): the order is fitted
    // where the error is asymptotic, over the four finest steps
    const std::vector<double> fine_steps(steps.end() - 4, steps.end()), fine_errors(errors.end() - 4, errors.end());
    const double observed = loglog_slope(fine_steps, fine_errors);
    std::cout << method << " on the viscous vortex from 10x rk4's limit: order " << observed << ", errors " << errors.front() << " to "
              << errors.back() << '\n';
    EXPECT_NEAR(observed, order, tolerance::order_band) << method;
  }
}

}  // namespace
}  // namespace stepwise
