// Height-field water: the seeds' three-level scheme against the exact evolution of its modes (closed form,
// and every mode of a random state through FFTW's DST-I), the continuous solution at second order, the
// discrete dispersion relation, the stability limit found by bisection against its derivation (and the
// seeds' condition), the scheme's energy, and the fast kernels bitwise against the plain loop.
#include "models/height_field.hpp"
#include "solvers/fd_jacobian.hpp"
#include "solvers/wave_step.hpp"
#include "verification/adequacy.hpp"
#include "run/measure.hpp"
#include "verification/order_fit.hpp"
#include "verification/stability.hpp"
#include "verification/tolerances.hpp"
#include "verification/wave_modes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <iostream>
#include <numbers>
#include <random>
#include <tuple>

namespace stepwise {
namespace {

double relative_max(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).lpNorm<Eigen::Infinity>() / b.lpNorm<Eigen::Infinity>();
}

Params wave(int size, double spacing, double c, double mu) {
  return {{"size", size}, {"spacing", spacing}, {"c", c}, {"mu", mu}};
}

TEST(Wave, SchemeMatchesTheExactDiscreteModeToRoundOff) {
  // mu = 10 overdamps the slowest mode (1, 1), which tests the closed form's real roots; a faster mode
  // there would decay below the round-off left in the slowest
  for (const auto& [mu, m, n] : {std::tuple{0.0, 3, 2}, {0.5, 3, 2}, {10.0, 1, 1}}) {
    Params p = wave(33, 0.03, 1.0, mu);
    p["mode_m"] = m;
    p["mode_n"] = n;
    p["amplitude"] = 0.01;
    const auto model = make_model("standing-wave", p);
    const WaveGridView grid = *model->as<WaveGridView>();
    const double dt = 0.9 * wave_stable_dt(grid);
    const long steps = 1000;
    // through `wave-fd` as `run` steps it: z^1 by Taylor from the mode at rest, then the three-level update
    const Measured run = run_and_measure(*model, "wave-fd", StepControl::fixed(dt), steps * dt, steps * dt);
    ASSERT_EQ(run.result.status, Status::ok) << run.result.message;
    const double lambda = laplacian_eigenvalue(32, grid.spacing, m, n);
    const SchemeMode mode = scheme_mode(grid, dt, lambda);
    const double a0 = 0.01, a1 = a0 * (1 - 0.5 * dt * dt * grid.c * grid.c * lambda);
    const Eigen::VectorXd expected = scheme_mode_amplitude(mode, a0, a1, steps) * wave_mode(33, m, n);
    const double error = relative_max(run.result.y_stop.head(33 * 33), expected);
    std::cout << "mu " << mu << ": " << steps << " steps, relative error against the exact discrete mode " << error << '\n';
    EXPECT_LT(error, tolerance::wave_modal) << "mu " << mu;
  }
}

TEST(Wave, SchemeConvergesToTheContinuousModeAtSecondOrder) {
  // the unit square, mode (1, 2), dt = d / (2c): error in z at t = 1 s against A sin sin a(t), a'' + mu a' + c^2 k^2 a = 0
  const double mu = 0.5, c = 1.0, t_end = 1.0;
  std::vector<double> spacings, errors;
  for (const int intervals : {16, 32, 64, 128}) {
    const double d = 1.0 / intervals;
    Params p = wave(intervals + 1, d, c, mu);
    p["mode_m"] = 1;
    p["mode_n"] = 2;
    p["amplitude"] = 1.0;
    const auto model = make_model("standing-wave", p);
    const Measured m = run_and_measure(*model, "wave-fd", StepControl::fixed(d / (2 * c)), t_end, t_end);
    ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
    const double k2 = std::numbers::pi * std::numbers::pi * 5;
    const Eigen::VectorXd continuous = mode_amplitude(c * c * k2, mu, 1.0, t_end).first * wave_mode(intervals + 1, 1, 2);
    const double error = (m.result.y_stop.head(continuous.size()) - continuous).lpNorm<Eigen::Infinity>();
    std::cout << "N " << intervals << ": error against the continuous mode " << error << '\n';
    spacings.push_back(d);
    errors.push_back(error);
  }
  const double order = loglog_slope(spacings, errors);
  std::cout << "observed order in d (dt = d/2c) " << order << '\n';
  EXPECT_NEAR(order, 2.0, tolerance::order_band);
}

TEST(Wave, EveryModeOfARandomStateEvolvesExactlyThroughTheFft) {
  const int points = 49;
  const Eigen::VectorXd z0 = random_wave_field(points, 1.0, 7);
  // the DST-I round trip scales by (2N)^2, which sine_coefficients / from_sine_coefficients divide out
  EXPECT_LT(relative_max(from_sine_coefficients(points, sine_coefficients(points, z0)), z0), tolerance::dst_round_trip);
  for (const double mu : {0.0, 2.0}) {
    const WaveGridView grid{points, 0.02, 1.0, mu};
    const double dt = 0.95 * wave_stable_dt(grid);
    const Eigen::VectorXd z1 = z0 + random_wave_field(points, 0.1, 8);
    const long steps = 3000;
    Eigen::VectorXd z_prev = z0, z = z1;
    run_wave_scheme(grid, dt, steps - 1, z_prev, z);
    const double error = relative_max(z, evolve_modes(grid, dt, z0, z1, steps));
    std::cout << "mu " << mu << ": " << steps << " steps, " << (points - 2) * (points - 2)
              << " modes, relative error of the scheme against the modes evolved exactly " << error << '\n';
    EXPECT_LT(error, tolerance::wave_modal) << "mu " << mu;
  }
}

TEST(Wave, EachModeOscillatesAtTheDiscreteDispersionRelation) {
  const int points = 33, N = 32;
  const WaveGridView grid{points, 0.02, 1.0, 0.0};
  const double dt = 0.8 * wave_stable_dt(grid);
  const int samples = 200;
  // every mode's amplitude over 200 steps of a random state
  std::vector<Eigen::VectorXd> a;
  Eigen::VectorXd z_prev = random_wave_field(points, 1.0, 3), z = random_wave_field(points, 1.0, 4);
  a.push_back(sine_coefficients(points, z_prev));
  for (int k = 0; k < samples; ++k) {
    a.push_back(sine_coefficients(points, z));
    run_wave_scheme(grid, dt, 1, z_prev, z);
  }
  double worst = 0, worst_continuous = 0;
  for (int m = 1; m < N; ++m)
    for (int n = 1; n < N; ++n) {
      const int index = (m - 1) * (N - 1) + (n - 1);
      double num = 0, den = 0;
      for (int k = 1; k + 1 < static_cast<int>(a.size()); ++k) {
        num += a[k][index] * (a[k + 1][index] + a[k - 1][index]);
        den += 2 * a[k][index] * a[k][index];
      }
      const double measured = std::acos(num / den) / dt;
      const double formula = scheme_mode_frequency(scheme_mode(grid, dt, laplacian_eigenvalue(N, grid.spacing, m, n)), dt);
      const double continuous = grid.c * std::numbers::pi * std::hypot(m, n) / (N * grid.spacing);
      worst = std::max(worst, std::abs(measured - formula) / formula);
      worst_continuous = std::max(worst_continuous, std::abs(formula - continuous) / continuous);
    }
  std::cout << "largest relative difference, measured against discrete dispersion " << worst
            << "; discrete against continuous frequency (numerical dispersion) " << worst_continuous << '\n';
  EXPECT_LT(worst, tolerance::wave_dispersion);
}

TEST(Wave, StabilityLimitMatchesTheDerivationAndTheSeedsConditionOnlyWithoutDamping) {
  const int points = 32;
  const long steps = 3000;
  for (const auto& [c, d] : {std::pair{1.0, 0.02}, {2.0, 0.05}, {0.5, 0.01}})
    for (const double mu : {0.0, 0.5, 2.0, 10.0}) {
      const WaveStability fd = wave_stability("wave-fd", points, d, c, mu, steps);
      std::cout << "c " << c << " d " << d << " mu " << mu << ": wave-fd limit measured " << fd.measured << " s, derived " << fd.derived
                << " s, seeds' condition " << fd.seeds << " s";
      EXPECT_NEAR(fd.measured / fd.derived, 1.0, tolerance::stability_match) << "c " << c << " d " << d << " mu " << mu;
      // the seeds' condition promises more than the scheme gives once there is damping: a run at it diverges
      if (fd.seeds > fd.derived * (1 + 2 * tolerance::stability_match)) {
        EXPECT_FALSE(wave_stays_bounded("wave-fd", points, d, c, mu, steps)(fd.seeds * 0.999));
      }
      if (c == 1.0) {
        // the second seed's scheme (symplectic Euler, damping explicit): limit shorter with damping
        const WaveStability se = wave_stability("symplectic-euler", points, d, c, mu, steps);
        std::cout << "; symplectic-euler measured " << se.measured << " s, derived " << se.derived << " s";
        EXPECT_NEAR(se.measured / se.derived, 1.0, tolerance::stability_match) << "symplectic-euler mu " << mu;
      }
      std::cout << '\n';
    }
}

// the stability regions' limits from a spectrum, against their closed forms: explicit Euler 2 / lambda on a real
// negative eigenvalue and no step at all on the imaginary axis, rk4 2 sqrt 2 / omega up the imaginary axis,
// implicit Euler any step on the left half-plane
TEST(Stability, SpectrumLimitsMatchTheRegionsClosedForms) {
  const double omega = 45.0, lambda = 30.0;
  Eigen::VectorXcd imaginary(2), real(1);
  imaginary << std::complex<double>(0, omega), std::complex<double>(0, -omega);
  real << -lambda;
  EXPECT_NEAR(*spectrum_stable_dt("euler", real) * lambda / 2, 1.0, tolerance::spectrum_limit_bisection);
  EXPECT_EQ(*spectrum_stable_dt("euler", imaginary), 0.0);
  EXPECT_NEAR(*spectrum_stable_dt("rk4", imaginary) * omega / (2 * std::numbers::sqrt2), 1.0, tolerance::spectrum_limit_bisection);
  EXPECT_TRUE(std::isinf(*spectrum_stable_dt("implicit-euler", imaginary)));
  EXPECT_FALSE(spectrum_stable_dt("symplectic-euler", imaginary).has_value());
}

// rk4 on the standing wave's 17^2 grid: the limit predicted from its (difference) Jacobian's spectrum is the one a
// random field measures, though the undamped modes come out of the difference Jacobian a little right of the axis
TEST(Stability, Rk4LimitFromTheWaveSpectrumIsTheMeasuredOne) {
  const int points = 17;
  const double spacing = 1.0 / 16, c = 1, mu = 0.5;
  const auto model = make_model("standing-wave", {{"size", points}, {"spacing", spacing}, {"c", c}, {"mu", mu}});
  const double predicted = *spectrum_stable_dt("rk4", jacobian_spectrum(*model, 0, model->initial_state()));
  const double measured = bisect_stability(wave_stays_bounded("rk4", points, spacing, c, mu, 2000), predicted / 2, predicted * 2,
                                           tolerance::stability_bisection_width);
  std::cout << "rk4 on the 17^2 wave: predicted " << predicted << " s, measured " << measured << " s\n";
  EXPECT_NEAR(measured / predicted, 1.0, tolerance::stability_match);
}

TEST(Wave, SchemeEnergyIsConservedWithoutDampingAndDecaysAsItsModesPredict) {
  const int points = 33;
  for (const double mu : {0.0, 2.0}) {
    const WaveGridView grid{points, 0.02, 1.0, mu};
    const double dt = 0.9 * wave_stable_dt(grid);
    const Eigen::VectorXd z0 = random_wave_field(points, 1.0, 5), z1 = z0 + random_wave_field(points, 0.1, 6);
    const double e0 = scheme_energy(grid, dt, z0, z1);
    Eigen::VectorXd z_prev = z0, z = z1;
    double previous = e0;
    bool rose = false;
    // undamped: long, to see any drift; damped: 4 s, the energy down to ~1e-4 of its start
    const long steps = mu == 0 ? 10000 : 300;
    for (long k = 0; k < steps; ++k) {
      run_wave_scheme(grid, dt, 1, z_prev, z);
      const double e = scheme_energy(grid, dt, z_prev, z);
      rose = rose || e > previous * (1 + tolerance::wave_energy_roundoff);
      previous = e;
    }
    if (mu == 0) {
      std::cout << "mu 0: relative energy change over " << steps << " steps " << (previous - e0) / e0 << '\n';
      EXPECT_LT(std::abs(previous - e0) / e0, tolerance::wave_energy_roundoff);
    } else {
      // the energy of the exactly evolved modes, at the same two levels
      const double predicted = scheme_energy(grid, dt, evolve_modes(grid, dt, z0, z1, steps), evolve_modes(grid, dt, z0, z1, steps + 1));
      std::cout << "mu " << mu << ": energy fell to " << previous / e0 << " of its start, the modes predict " << predicted / e0 << '\n';
      EXPECT_NEAR(previous / predicted, 1.0, tolerance::wave_energy_modal);
      EXPECT_FALSE(rose) << "the damped scheme's energy may only fall";
    }
  }
}

// 250 points: the step's two grids (1.0 MB) held in cache, 520 points: 4.3 MB, streamed with prefetching
// (wave_step.cpp picks by the L2's size, 1 MB here); the blocked pass pipelined over 1, 2 and 3 threads (8
// steps shared 8, 4 + 4 and 2 + 3 + 3). The reference is the seeds' formula cell by cell into a third grid
class WaveKernels : public ::testing::TestWithParam<int> {};
INSTANTIATE_TEST_SUITE_P(Grid, WaveKernels, ::testing::Values(250, 520));

TEST_P(WaveKernels, InPlaceBlockedAndThreadedStepsAreBitwiseTheSeedsFormula) {
  const int points = GetParam(), steps = 8;
  const WaveGridView grid{points, 0.02, 1.0, 0.5};
  const WaveCoefficients k = wave_coefficients(grid, 0.9 * wave_stable_dt(grid));
  const Eigen::VectorXd z0 = random_wave_field(points, 1.0, 1), z1 = random_wave_field(points, 1.0, 2);
  Eigen::VectorXd plain_prev = z0, plain = z1, next = Eigen::VectorXd::Zero(z0.size());
  for (int s = 0; s < steps; ++s) {
    for (int i = 1; i < points - 1; ++i)
      for (int j = i * points + 1; j < (i + 1) * points - 1; ++j) next[j] = wave_cell(k, plain[j], plain_prev[j], neighbour_sum(plain.data(), j, points));
    plain_prev.swap(plain);
    plain.swap(next);
  }
  const size_t bytes = sizeof(double) * static_cast<size_t>(z0.size());
  for (const int threads : {1, 2, 3}) {
    Eigen::VectorXd blocked_prev = z0, blocked = z1;
    wave_steps_blocked(k, points, steps, blocked_prev.data(), blocked.data(), threads);
    EXPECT_EQ(std::memcmp(blocked.data(), plain.data(), bytes), 0) << "blocked, " << threads << " threads";
    EXPECT_EQ(std::memcmp(blocked_prev.data(), plain_prev.data(), bytes), 0) << "blocked, " << threads << " threads";
    Eigen::VectorXd a = z0, b = z1;
    for (int s = 0; s < steps; ++s) {
      wave_step(k, points, a.data(), b.data(), threads);
      a.swap(b);
    }
    EXPECT_EQ(std::memcmp(b.data(), plain.data(), bytes), 0) << "in place, " << threads << " threads";
    EXPECT_EQ(std::memcmp(a.data(), plain_prev.data(), bytes), 0) << "in place, " << threads << " threads";
  }
}

TEST(Wave, ShallowWaterTendsToTheWaveEquationAtFirstOrderInTheAmplitude) {
  // the shallow water equations linearised are the wave equation with c^2 = g H on the same stencil, so
  // their difference for a drop of height A is A times a first-order term in A / H: it falls tenfold with
  // A, to the order's own correction (tolerance); were the linear parts different it would not fall at all
  std::vector<double> departures;
  for (const double ratio : {1e-4, 1e-3, 1e-2}) {
    departures.push_back(linear_wave_departure(ratio).relative);
    std::cout << "A/H = " << ratio << ": |eta - z| / |z| = " << departures.back() << '\n';
  }
  for (size_t k = 0; k + 1 < departures.size(); ++k)
    EXPECT_NEAR(departures[k + 1] / departures[k] / 10, 1.0, tolerance::shallow_water_first_order) << k;
}

TEST(Wave, ShallowWaterEnergyIsConservedToTheGridsSecondOrder) {
  // a wide bump of 30% of the depth, undamped, for 0.3 s on the same square at spacings d, d/2: the energy's
  // relative change must fall fourfold (the non-linear terms are in it: a factor wrong there stops the fall)
  std::vector<double> changes;
  for (const auto& [size, spacing, dt] : {std::tuple{95, 0.01, 1e-3}, std::tuple{189, 0.005, 5e-4}}) {
    const auto model = make_model("shallow-water", {{"size", size}, {"spacing", spacing}, {"mu", 0}, {"drop_height", 0.03},
                                                    {"drop_radius", 0.2}, {"drop_x", 0.47}, {"drop_y", 0.47}});
    const Measured m = run_and_measure(*model, "rk4", StepControl::fixed(dt), 0.3, 0.3);
    ASSERT_EQ(m.result.status, Status::ok);
    const double e0 = *model->energy(model->initial_state()), e1 = *model->energy(m.result.y_stop);
    changes.push_back(std::abs(e1 - e0) / e0);
    std::cout << size << " points: |E(0.3) - E(0)| / E(0) = " << changes.back() << '\n';
  }
  EXPECT_GT(changes[0] / changes[1], tolerance::shallow_water_energy_second_order);
}

TEST(Wave, SparseJacobianMatchesCentralDifferences) {
  const auto model = make_model("water-drop", {{"size", 7}, {"drop_x", 0.06}, {"drop_y", 0.06}, {"mu", 0.7}});
  Eigen::VectorXd y = Eigen::VectorXd::Zero(model->size());
  y.head(49) = random_wave_field(7, 1.0, 9);
  y.tail(49) = random_wave_field(7, 1.0, 10);
  Eigen::SparseMatrix<double> sparse;
  model->as<SparseJacobian>()->sparse_jacobian(0, y, sparse);
  Eigen::MatrixXd fd(model->size(), model->size());
  fd_jacobian(*model, 0, y, fd);
  const Eigen::MatrixXd analytic(sparse);
  EXPECT_LT((analytic - fd).lpNorm<Eigen::Infinity>(), tolerance::jacobian_fd * (1 + analytic.lpNorm<Eigen::Infinity>()));
}

TEST(Wave, MethodOfLinesThroughCvodeAgreesWithTheExactSemiDiscreteMode) {
  Params p = wave(33, 0.03, 1.0, 0.5);
  p["amplitude"] = 0.01;
  const auto model = make_model("standing-wave", p);
  for (const char* method : {"cvode-adams", "cvode-bdf"}) {
    const Measured m = run_and_measure(*model, method, StepControl::adaptive(1e-10, 1e-14), 2.0, 2.0);
    ASSERT_EQ(m.result.status, Status::ok) << method << ": " << m.result.message;
    const double size = model->exact(2.0).lpNorm<Eigen::Infinity>();
    std::cout << method << " rtol 1e-10: error " << *m.error << " (solution size " << size << "), " << m.result.stats.steps << " steps\n";
    EXPECT_LT(*m.error, tolerance::method_of_lines_rtol_multiple * 1e-10 * size) << method;
  }
}

}  // namespace
}  // namespace stepwise
