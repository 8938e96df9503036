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
  static constexpr int size = inline_f ? N : 0;  // PlainStepping: advance() offered

  explicit Rk4(const CountedSystem& s, KernelOr<F> f = {}) : system_(s), f_(f), k1_(s.size()), k2_(s.size()), k3_(s.size()), k4_(s.size()), tmp_(s.size()) {}
  STEPWISE_SCALAR_STORES bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    if constexpr (inline_f) {
      counted(1);
      norm_ = advance(t, h, y.data(), y_next.data());
    } else {
      double* k[4] = {k1_.data(), k2_.data(), k3_.data(), k4_.data()};
      const auto f = [&](int i, double ts, const double*, double*) {
        if (i == 0) system_.rhs(ts, y, k1_);
        else system_.rhs(ts, stage_, i == 1 ? k2_ : i == 2 ? k3_ : k4_);
      };
      norm_ = stages(f, t, h, y.data(), k, tmp_.data(), y_next.data(), y.size());
    }
    return true;
  }
  // the stages k1..k4 and the stage's argument in local arrays the compiler keeps in registers
  STEPWISE_SCALAR_STORES double advance(double t, double h, const double* y0, double* y1) const
    requires inline_f
  {
    std::array<std::array<double, N>, 5> local;
    double* k[4] = {local[0].data(), local[1].data(), local[2].data(), local[3].data()};
    const auto f = [&](int, double ts, const double* at, double* out) { f_(ts, at, out); };
    return stages(f, t, h, y0, k, local[4].data(), y1, N);
  }
  void counted(long steps) const { system_.stats().rhs_evals += 4 * steps; }

 private:
  // the method, once for both paths: f(i, ts, at, k[i]) puts f(ts, at) into k[i] (at: y0, then tmp); |y1|inf
  template <class CallF>
  STEPWISE_SCALAR_STORES static double stages(const CallF& f, double t, double h, const double* y0, double* const* k, double* tmp, double* y1,
                                              Eigen::Index size) {
    const Eigen::Index n = N > 0 ? N : size;
    f(0, t, y0, k[0]);
    for (Eigen::Index i = 0; i < n; ++i) tmp[i] = y0[i] + (h / 2) * k[0][i];
    f(1, t + h / 2, tmp, k[1]);
    for (Eigen::Index i = 0; i < n; ++i) tmp[i] = y0[i] + (h / 2) * k[1][i];
    f(2, t + h / 2, tmp, k[2]);
    for (Eigen::Index i = 0; i < n; ++i) tmp[i] = y0[i] + h * k[2][i];
    f(3, t + h, tmp, k[3]);
    RunningNorm norm;
    for (Eigen::Index i = 0; i < n; ++i) {
      y1[i] = y0[i] + (h / 6) * (k[0][i] + 2 * k[1][i] + 2 * k[2][i] + k[3][i]);
      norm.add(y1[i]);
    }
    return norm.value();
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
      .family = Family::rk4,
      .source = Source::hand_written,
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
