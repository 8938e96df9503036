// `wave-fd`: the seeds' three-level scheme (wave_step.hpp) as a stepper on y = (z, v).
//
// The scheme carries z^{k-1} and z^k, the state carries z and v: the stepper keeps z^{k-1} itself between
// consecutive steps of one size, and reports v^{k+1} = (3 z^{k+1} - 4 z^k + z^{k-1}) / (2 dt), the
// second-order one-sided difference. At the start, and whenever the step is not the continuation of its
// last one (after an event, a shortened step, a re-step), it starts afresh as the seeds do, z^1 from the
// shape and the velocity by Taylor's expansion z^1 = z^0 + dt v^0 + dt^2/2 a^0 with
// a^0 = c^2 Lap z^0 - mu v^0, and v^1 by the trapezoid rule on dv/dt = a (velocity Verlet).
#include "fixed_step.hpp"
#include "run_support.hpp"
#include "wave_step.hpp"

#include <cmath>

namespace stepwise {

namespace {

class WaveFd final : public FixedStepper {
 public:
  explicit WaveFd(const CountedSystem& s)
      : system_(s), grid_(*s.wave_grid()), n_(grid_.points), cells_(static_cast<Eigen::Index>(n_) * n_), z_prev_(cells_) {}

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    ++system_.stats().rhs_evals;  // one Laplacian per step
    const double* z = y.data();
    const double* v = z + cells_;
    double* z1 = y_next.data();
    double* v1 = z1 + cells_;
    // the boundary holds still (y_next may hold anything: only the interior is written below)
    for (int b = 0; b < n_; ++b)
      for (const Eigen::Index cell : {Eigen::Index(b), Eigen::Index(n_ - 1) * n_ + b, Eigen::Index(b) * n_, Eigen::Index(b) * n_ + n_ - 1})
        z1[cell] = v1[cell] = 0;
    // a step the loop shortened by rounding alone to land on an output time (1e-9 dt, its snap) continues
    const bool continuing = history_ && std::abs(h - h_) <= 1e-9 * h_ && std::abs(t - t_last_) <= 1e-9 * h_ && y.data() == last_;
    if (continuing) {
      for (int i = 1; i < n_ - 1; ++i)
        for (int j = i * n_ + 1; j < (i + 1) * n_ - 1; ++j) {
          const double z_prev = z_prev_[j];
          z_prev_[j] = z[j];
          z1[j] = wave_cell(k_, z[j], z_prev, neighbour_sum(z, j, n_));
          v1[j] = (3 * z1[j] - 4 * z[j] + z_prev) / (2 * h_);
        }
    } else {
      // velocity Verlet: z^1 = z + h v + h^2/2 a(z, v), v^1 = v + h/2 (a(z, v) + a(z^1, v^1)), the damping
      // in a(z^1, v^1) solved for (a first-order v^1 = v + h a would make a restart at every step grow)
      const double c2 = grid_.c * grid_.c / (grid_.spacing * grid_.spacing);
      auto laplacian = [&](const double* u, int j) { return c2 * (neighbour_sum(u, j, n_) - 4 * u[j]); };
      for (int i = 1; i < n_ - 1; ++i)
        for (int j = i * n_ + 1; j < (i + 1) * n_ - 1; ++j) {
          const double a = laplacian(z, j) - grid_.mu * v[j];
          z_prev_[j] = z[j];
          z1[j] = z[j] + h * v[j] + (h * h / 2) * a;
          v1[j] = v[j] + (h / 2) * a;
        }
      for (int i = 1; i < n_ - 1; ++i)
        for (int j = i * n_ + 1; j < (i + 1) * n_ - 1; ++j) v1[j] = (v1[j] + (h / 2) * laplacian(z1, j)) / (1 + grid_.mu * h / 2);
    }
    if (!continuing) {
      h_ = h;
      k_ = wave_coefficients(grid_, h);
    }
    history_ = true;
    t_last_ = t + h;
    last_ = y_next.data();
    return true;
  }
  void reset() override { history_ = false; }

 private:
  const CountedSystem& system_;
  WaveGridView grid_;
  int n_;                         // grid points per side
  Eigen::Index cells_;            // n^2
  Eigen::VectorXd z_prev_;        // z^{k-1} (n^2), valid while history_
  bool history_ = false;          // the last step's end is where the next one starts
  double h_ = 0, t_last_ = 0;     // the last step's size and end
  const double* last_ = nullptr;  // the buffer it wrote
  WaveCoefficients k_;            // for h_
};

}  // namespace

std::unique_ptr<FixedStepper> make_wave_fd(const CountedSystem& system) { return std::make_unique<WaveFd>(system); }

}  // namespace stepwise
