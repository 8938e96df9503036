// rk4: the classical fourth-order Runge-Kutta method.
#include "solvers/fixed_step.hpp"
#include "solvers/run_support.hpp"
#include "solvers/stability.hpp"

namespace stepwise {
namespace {

// classical fourth-order Runge-Kutta (Kutta 1901), four calls of f per step. Each stage is one plain loop
// over the state (no temporaries, nothing allocated) and the last one measures |y_next|inf on its way, so
// on a small system the step costs its four calls of f and little else (bench_rk4); N: the state's size
// where known at compile time (make_sized), else 0
template <int N>
class Rk4 final : public FixedStepper {
 public:
  explicit Rk4(const CountedSystem& s) : system_(s), k1_(s.size()), k2_(s.size()), k3_(s.size()), k4_(s.size()), tmp_(s.size()) {}
  STEPWISE_SCALAR_STORES bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    const Eigen::Index n = N > 0 ? N : y.size();
    const double* y0 = y.data();
    const double *k1 = k1_.data(), *k2 = k2_.data(), *k3 = k3_.data(), *k4 = k4_.data();
    double* tmp = tmp_.data();
    system_.rhs(t, y, k1_);
    for (Eigen::Index i = 0; i < n; ++i) tmp[i] = y0[i] + (h / 2) * k1[i];
    system_.rhs(t + h / 2, stage_, k2_);
    for (Eigen::Index i = 0; i < n; ++i) tmp[i] = y0[i] + (h / 2) * k2[i];
    system_.rhs(t + h / 2, stage_, k3_);
    for (Eigen::Index i = 0; i < n; ++i) tmp[i] = y0[i] + h * k3[i];
    system_.rhs(t + h, stage_, k4_);
    double* y1 = y_next.data();
    RunningNorm norm;
    for (Eigen::Index i = 0; i < n; ++i) {
      y1[i] = y0[i] + (h / 6) * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
      norm.add(y1[i]);
    }
    norm_ = norm.value();
    return true;
  }

 private:
  const CountedSystem& system_;
  Eigen::VectorXd k1_, k2_, k3_, k4_, tmp_;
  // f's argument at the inner stages, made once: a Ref<const> built per call is a measurable part of a
  // pendulum's step (its destructor frees its empty fallback copy)
  const Eigen::Ref<const Eigen::VectorXd> stage_{tmp_};
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
      .make = fixed_steps([](const CountedSystem& system) { return make_sized<Rk4>(system.size(), system); }),
      // no closed form on a damped mode: the step where |R(h lambda)| reaches 1 on its pair of eigenvalues
      // (h w = 2 sqrt 2 undamped: the region's reach up the imaginary axis)
      .stability = {.R = rk4_stability,
                    .oscillator_dt = [](double omega, double damping) {
                      return largest_stable_step(rk4_stability, oscillator_eigenvalues(omega, damping));
                    }},
  });
}

}  // namespace stepwise
