// The seeds' three-level scheme as a stepper, its levels advanced by a subclass (three_level_wave.hpp)
#include "three_level_wave.hpp"

#include <cmath>

namespace stepwise {

ThreeLevelWaveStepper::ThreeLevelWaveStepper(const CountedSystem& s)
    : system_(s), grid_(*s.as<WaveGridView>()), n_(grid_.points), cells_(static_cast<Eigen::Index>(n_) * n_), z_prev_(cells_) {}

bool ThreeLevelWaveStepper::step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) {
  ++system_.stats().rhs_evals;  // one Laplacian per step
  const double* z = y.data();
  const double* v = z + cells_;
  double* z1 = y_next.data();
  double* v1 = z1 + cells_;
  // f(cell) for every cell on the grid's boundary
  const auto on_boundary = [this](auto&& f) {
    for (int b = 0; b < n_; ++b)
      for (const Eigen::Index cell : {Eigen::Index(b), Eigen::Index(n_ - 1) * n_ + b, Eigen::Index(b) * n_, Eigen::Index(b) * n_ + n_ - 1}) f(cell);
  };
  // the boundary holds still (y_next may hold anything: only the interior is written below)
  on_boundary([&](Eigen::Index cell) { z1[cell] = v1[cell] = 0; });
  // a step the loop shortened by rounding alone to land on an output time (1e-9 dt, its snap) continues
  const bool continuing = history_ && std::abs(h - h_) <= 1e-9 * h_ && std::abs(t - t_last_) <= 1e-9 * h_ && y.data() == last_;
  if (continuing) {
    if (!advance(k_, z_prev_.data(), z, z1, fresh_, failure)) return false;
    fresh_ = false;
    for (int i = 1; i < n_ - 1; ++i)
      for (int j = i * n_ + 1; j < (i + 1) * n_ - 1; ++j) {
        v1[j] = wave_velocity(h_, z1[j], z[j], z_prev_[j]);
        z_prev_[j] = z[j];
      }
  } else {
    const double c2 = grid_.c * grid_.c / (grid_.spacing * grid_.spacing);
    for (int i = 1; i < n_ - 1; ++i)
      for (int j = i * n_ + 1; j < (i + 1) * n_ - 1; ++j) {
        const double a = wave_acceleration(c2, grid_.mu, neighbour_sum(z, j, n_), z[j], v[j]);
        z_prev_[j] = z[j];
        const auto [zj, vj] = wave_restart_first(h, a, z[j], v[j]);
        z1[j] = zj;
        v1[j] = vj;
      }
    for (int i = 1; i < n_ - 1; ++i)
      for (int j = i * n_ + 1; j < (i + 1) * n_ - 1; ++j)
        v1[j] = wave_restart_second(h, grid_.mu, v1[j], wave_laplacian(c2, neighbour_sum(z1, j, n_), z1[j]));
    // the boundary of z^{k-1}, as of z: held still
    on_boundary([&](Eigen::Index cell) { z_prev_[cell] = z[cell]; });
    h_ = h;
    k_ = wave_coefficients(grid_, h);
    fresh_ = true;
  }
  history_ = true;
  t_last_ = t + h;
  last_ = y_next.data();
  return true;
}

}  // namespace stepwise
