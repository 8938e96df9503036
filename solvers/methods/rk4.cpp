// rk4: the classical fourth-order Runge-Kutta method.
#include "solvers/fixed_step.hpp"
#include "solvers/run_support.hpp"
#include "solvers/stability.hpp"

namespace stepwise {
namespace {

// classical fourth-order Runge-Kutta (Kutta 1901), four calls of f per step
class Rk4 final : public FixedStepper {
 public:
  explicit Rk4(const CountedSystem& s) : system_(s), k1_(s.size()), k2_(s.size()), k3_(s.size()), k4_(s.size()), tmp_(s.size()) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    system_.rhs(t, y, k1_);
    tmp_ = y + (h / 2) * k1_;
    system_.rhs(t + h / 2, tmp_, k2_);
    tmp_ = y + (h / 2) * k2_;
    system_.rhs(t + h / 2, tmp_, k3_);
    tmp_ = y + h * k3_;
    system_.rhs(t + h, tmp_, k4_);
    y_next = y + (h / 6) * (k1_ + 2 * k2_ + 2 * k3_ + k4_);
    return true;
  }

 private:
  const CountedSystem& system_;
  Eigen::VectorXd k1_, k2_, k3_, k4_, tmp_;
};

std::complex<double> rk4_stability(std::complex<double> z) { return 1.0 + z * (1.0 + z / 2.0 * (1.0 + z / 3.0 * (1.0 + z / 4.0))); }

}  // namespace

void register_rk4_methods(MethodTable& table) {
  table.add({
      .name = "rk4",
      .family = "rk4",
      .source = "hand-written",
      .description = "explicit, fixed step",
      .order = {4, 4, "4"},
      .stepping = Stepping::fixed,
      .make = fixed_steps([](const CountedSystem& system) { return std::make_unique<Rk4>(system); }),
      // no closed form on a damped mode: the step where |R(h lambda)| reaches 1 on its pair of eigenvalues
      // (h w = 2 sqrt 2 undamped: the region's reach up the imaginary axis)
      .stability = {.R = rk4_stability,
                    .oscillator_dt = [](double omega, double damping) {
                      return largest_stable_step(rk4_stability, oscillator_eigenvalues(omega, damping));
                    }},
  });
}

}  // namespace stepwise
