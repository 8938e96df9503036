// euler: explicit Euler, the first method the seeds teach.
#include "solvers/inline_stepper.hpp"

namespace stepwise {
namespace {

// y1 = y0 + h f(t0, y0): one call of f and one loop that also measures |y1|inf; N and F as in rk4.cpp
template <int N, class F>
class Euler final : public PlainStepping<Euler<N, F>> {
  using FixedStepper::norm_;

  static constexpr bool inline_f = !std::is_void_v<F>;

 public:
  static constexpr int size = inline_f ? N : 0;  // PlainStepping: advance() offered

  explicit Euler(const CountedSystem& s, KernelOr<F> kernel = {}) : system_(s), kernel_(kernel), f_(s.size()) {}
  STEPWISE_SCALAR_STORES bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    if constexpr (inline_f) {
      counted(1);
      norm_ = advance(t, h, y.data(), y_next.data());
    } else {
      system_.rhs(t, y, f_);
      norm_ = update(h, y.data(), f_.data(), y_next.data(), y.size());
    }
    return true;
  }
  double advance(double t, double h, const double* y0, double* y1) const
    requires inline_f
  {
    std::array<double, N> f;
    kernel_(t, y0, f.data());
    return update(h, y0, f.data(), y1, N);
  }
  void counted(long steps) const { system_.stats().rhs_evals += steps; }

 private:
  // y1 = y0 + h f; |y1|inf
  static double update(double h, const double* y0, const double* f, double* y1, Eigen::Index n) {
    RunningNorm norm;
    for (Eigen::Index i = 0; i < (N > 0 ? N : n); ++i) {
      y1[i] = y0[i] + h * f[i];
      norm.add(y1[i]);
    }
    return norm.value();
  }

  const CountedSystem& system_;
  [[no_unique_address]] KernelOr<F> kernel_;
  Eigen::VectorXd f_;
};

}  // namespace

void register_euler_methods(MethodTable& table) {
  table.add({
      .name = "euler",
      .family = Family::euler,
      .source = Source::hand_written,
      .description = "explicit, fixed step",
      .order = {1, 1, "1"},
      .stepping = Stepping::fixed,
      .make = fixed_steps([](const CountedSystem& system) { return make_inline_or_sized<Euler>(system); }),
      // |1 + h lambda| <= 1 at lambda = -a + i sqrt(w^2 - a^2), |lambda| = w: h < 2 a / w^2, none at all undamped
      .stability = {.R = [](std::complex<double> z) { return 1.0 + z; },
                    .oscillator_dt = [](double omega, double damping) { return 2 * damping / (omega * omega); }},
  });
}

}  // namespace stepwise
