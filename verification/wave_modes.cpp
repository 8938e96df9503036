#include "wave_modes.hpp"

#include "models/height_field.hpp"
#include "solvers/wave_step.hpp"

#include <fftw3.h>
#include <fmt/format.h>

#include <cmath>
#include <complex>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

namespace stepwise {

Eigen::VectorXd random_wave_field(int points, double scale, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-scale, scale);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(points) * points);
  for (int i = 1; i < points - 1; ++i)
    for (int j = 1; j < points - 1; ++j) z[static_cast<Eigen::Index>(i) * points + j] = u(rng);
  return z;
}

namespace {

// DST-I in both dimensions of an (N-1) x (N-1) array (FFTW_RODFT00), in place of a copy
Eigen::VectorXd dst2(int inner, const Eigen::VectorXd& in) {
  Eigen::VectorXd x = in, y(in.size());
  const std::unique_ptr<fftw_plan_s, decltype(&fftw_destroy_plan)> plan(
      fftw_plan_r2r_2d(inner, inner, x.data(), y.data(), FFTW_RODFT00, FFTW_RODFT00, FFTW_ESTIMATE), &fftw_destroy_plan);
  if (!plan) throw std::runtime_error(fmt::format("fftw_plan_r2r_2d({0}, {0}, RODFT00) returned no plan", inner));
  fftw_execute(plan.get());
  return y;
}

}  // namespace

Eigen::VectorXd sine_coefficients(int points, const Eigen::VectorXd& z) {
  const int N = points - 1, inner = N - 1;
  Eigen::VectorXd interior(static_cast<Eigen::Index>(inner) * inner);
  for (int i = 0; i < inner; ++i)
    for (int j = 0; j < inner; ++j) interior[i * inner + j] = z[(i + 1) * points + (j + 1)];
  return dst2(inner, interior) / (static_cast<double>(N) * N);
}

Eigen::VectorXd from_sine_coefficients(int points, const Eigen::VectorXd& a) {
  const int inner = points - 2;
  const Eigen::VectorXd interior = dst2(inner, a) / 4;
  Eigen::VectorXd z = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(points) * points);
  for (int i = 0; i < inner; ++i)
    for (int j = 0; j < inner; ++j) z[(i + 1) * points + (j + 1)] = interior[i * inner + j];
  return z;
}

SchemeMode scheme_mode(const WaveGridView& grid, double dt, double lambda) {
  const long double denominator = 2 + static_cast<long double>(grid.mu) * dt;
  const long double c2dt2 = static_cast<long double>(grid.c) * grid.c * dt * dt;
  return {(2 - c2dt2 * lambda) / denominator, (2 - static_cast<long double>(grid.mu) * dt) / denominator};
}

double scheme_mode_amplitude(const SchemeMode& mode, double a0, double a1, long k) {
  const long double B = mode.B, C = mode.C, discriminant = B * B - C;
  if (discriminant < 0) {
    const long double rho = std::sqrt(C), theta = std::acos(B / rho);
    const long double q = (a1 / rho - a0 * std::cos(theta)) / std::sin(theta);
    return static_cast<double>(std::pow(rho, k) * (a0 * std::cos(k * theta) + q * std::sin(k * theta)));
  }
  if (discriminant > 0) {
    const long double s = std::sqrt(discriminant), r1 = B + s, r2 = B - s;
    const long double alpha = (a1 - a0 * r2) / (r1 - r2);
    return static_cast<double>(alpha * std::pow(r1, k) + (a0 - alpha) * std::pow(r2, k));
  }
  return static_cast<double>((a0 + k * (a1 / B - a0)) * std::pow(B, k));
}

double scheme_mode_frequency(const SchemeMode& mode, double dt) {
  return static_cast<double>(std::acos(mode.B / std::sqrt(mode.C))) / dt;
}

Eigen::VectorXd evolve_modes(const WaveGridView& grid, double dt, const Eigen::VectorXd& z0, const Eigen::VectorXd& z1, long k) {
  const int N = grid.points - 1, inner = N - 1;
  const Eigen::VectorXd a0 = sine_coefficients(grid.points, z0), a1 = sine_coefficients(grid.points, z1);
  Eigen::VectorXd a(a0.size());
  for (int m = 1; m <= inner; ++m)
    for (int n = 1; n <= inner; ++n) {
      const int index = (m - 1) * inner + (n - 1);
      const SchemeMode mode = scheme_mode(grid, dt, laplacian_eigenvalue(N, grid.spacing, m, n));
      a[index] = scheme_mode_amplitude(mode, a0[index], a1[index], k);
    }
  return from_sine_coefficients(grid.points, a);
}

double scheme_energy(const WaveGridView& grid, double dt, const Eigen::VectorXd& z, const Eigen::VectorXd& z_next) {
  const int n = grid.points;
  double kinetic = 0, potential = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int k = i * n + j;
      const double rate = (z_next[k] - z[k]) / dt;
      kinetic += rate * rate;
      for (const int neighbour : {j + 1 < n ? k + 1 : -1, i + 1 < n ? k + n : -1})
        if (neighbour >= 0) potential += (z_next[neighbour] - z_next[k]) * (z[neighbour] - z[k]);
    }
  return grid.spacing * grid.spacing * kinetic / 2 + grid.c * grid.c * potential / 2;
}

void run_wave_scheme(const WaveGridView& grid, double dt, long steps, Eigen::VectorXd& z_prev, Eigen::VectorXd& z) {
  const WaveCoefficients k = wave_coefficients(grid, dt);
  for (long s = 0; s < steps; ++s) {
    wave_step(k, grid.points, z_prev.data(), z.data());
    z_prev.swap(z);
  }
}

void run_wave_scheme_float32(const WaveGridView& grid, double dt, long steps, Eigen::VectorXf& z_prev, Eigen::VectorXf& z) {
  const BasicWaveCoefficients<float> k = to_float(wave_coefficients(grid, dt));
  const int n = grid.points;
  for (long s = 0; s < steps; ++s) {
    for (int i = 1; i < n - 1; ++i)
      for (int j = i * n + 1; j < (i + 1) * n - 1; ++j) z_prev[j] = wave_cell(k, z[j], z_prev[j], neighbour_sum(z.data(), j, n));
    z_prev.swap(z);
  }
}

void run_symplectic_wave_float32(const WaveGridView& grid, double dt, long steps, Eigen::VectorXf& z, Eigen::VectorXf& v) {
  const int n = grid.points;
  const float c2 = static_cast<float>(grid.c * grid.c / (grid.spacing * grid.spacing)), mu = static_cast<float>(grid.mu), h = static_cast<float>(dt);
  for (long s = 0; s < steps; ++s) {
    for (int i = 1; i < n - 1; ++i)
      for (int j = i * n + 1; j < (i + 1) * n - 1; ++j) v[j] = v[j] + h * wave_acceleration(c2, mu, neighbour_sum(z.data(), j, n), z[j], v[j]);
    for (int i = 1; i < n - 1; ++i)
      for (int j = i * n + 1; j < (i + 1) * n - 1; ++j) z[j] = z[j] + h * v[j];
  }
}

}  // namespace stepwise
