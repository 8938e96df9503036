// rk4: the classical fourth-order Runge-Kutta method.
#include "solvers/inline_stepper.hpp"
#include "solvers/stability.hpp"

namespace stepwise {
namespace {

// classical fourth-order Runge-Kutta (Kutta 1901), four calls of f per step. Each stage is one plain loop
// over the state (no temporaries, nothing allocated) and the last one measures |y_next|inf on its way, so
// on a small system the step costs its four calls of f and little else (bench_rk4); N: the state's size
// where known at compile time (make_sized), else 0. F: the model's f called inline, the stages then in
// local arrays the compiler keeps in registers (solvers/inline_stepper.hpp), or void: through the system
template <int N, class F>
class Rk4 final : public PlainStepping<Rk4<N, F>> {
  using FixedStepper::norm_;

  static constexpr bool inline_f = !std::is_void_v<F>;

 public:
  explicit Rk4(const CountedSystem& s, KernelOr<F> f = {}) : system_(s), f_(f), k1_(s.size()), k2_(s.size()), k3_(s.size()), k4_(s.size()), tmp_(s.size()) {}
  STEPWISE_SCALAR_STORES bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    const Eigen::Index n = N > 0 ? N : y.size();
    std::array<std::array<double, inline_f ? N : 0>, 5> local;  // k1..k4 and the stage's argument, inline
    const double* y0 = y.data();
    double* k[4];
    double* tmp;
    if constexpr (inline_f) {
      for (int i = 0; i < 4; ++i) k[i] = local[i].data();
      tmp = local[4].data();
      system_.stats().rhs_evals += 4;
    } else {
      k[0] = k1_.data(), k[1] = k2_.data(), k[2] = k3_.data(), k[3] = k4_.data();
      tmp = tmp_.data();
    }
    // f at stage i (0: at y, else at tmp) into k[i]
    const auto f = [&](int i, double ts) {
      if constexpr (inline_f) f_(ts, i == 0 ? y0 : tmp, k[i]);
      else if (i == 0) system_.rhs(ts, y, k1_);
      else system_.rhs(ts, stage_, i == 1 ? k2_ : i == 2 ? k3_ : k4_);
    };
    f(0, t);
    for (Eigen::Index i = 0; i < n; ++i) tmp[i] = y0[i] + (h / 2) * k[0][i];
    f(1, t + h / 2);
    for (Eigen::Index i = 0; i < n; ++i) tmp[i] = y0[i] + (h / 2) * k[1][i];
    f(2, t + h / 2);
    for (Eigen::Index i = 0; i < n; ++i) tmp[i] = y0[i] + h * k[2][i];
    f(3, t + h);
    double* y1 = y_next.data();
    RunningNorm norm;
    for (Eigen::Index i = 0; i < n; ++i) {
      y1[i] = y0[i] + (h / 6) * (k[0][i] + 2 * k[1][i] + 2 * k[2][i] + k[3][i]);
      norm.add(y1[i]);
    }
    norm_ = norm.value();
    return true;
  }

 private:
  const CountedSystem& system_;
  [[no_unique_address]] KernelOr<F> f_;
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
      .make = fixed_steps([](const CountedSystem& system) { return make_inline_or_sized<Rk4>(system); }),
      // no closed form on a damped mode: the step where |R(h lambda)| reaches 1 on its pair of eigenvalues
      // (h w = 2 sqrt 2 undamped: the region's reach up the imaginary axis)
      .stability = {.R = rk4_stability,
                    .oscillator_dt = [](double omega, double damping) {
                      return largest_stable_step(rk4_stability, oscillator_eigenvalues(omega, damping));
                    }},
  });
}

}  // namespace stepwise
