// euler: explicit Euler, the first method the seeds teach.
#include "solvers/fixed_step.hpp"
#include "solvers/run_support.hpp"

namespace stepwise {
namespace {

// y1 = y0 + h f(t0, y0): one call of f and one loop that also measures |y1|inf; N as in rk4.cpp
template <int N>
class Euler final : public FixedStepper {
 public:
  explicit Euler(const CountedSystem& s) : system_(s), f_(s.size()) {}
  STEPWISE_SCALAR_STORES bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    system_.rhs(t, y, f_);
    const double *y0 = y.data(), *f = f_.data();
    double* y1 = y_next.data();
    RunningNorm norm;
    for (Eigen::Index i = 0; i < (N > 0 ? N : y.size()); ++i) {
      y1[i] = y0[i] + h * f[i];
      norm.add(y1[i]);
    }
    norm_ = norm.value();
    return true;
  }

 private:
  const CountedSystem& system_;
  Eigen::VectorXd f_;
};

}  // namespace

void register_euler_methods(MethodTable& table) {
  table.add({
      .name = "euler",
      .family = "euler",
      .source = "hand-written",
      .description = "explicit, fixed step",
      .order = {1, 1, "1"},
      .stepping = Stepping::fixed,
      .make = fixed_steps([](const CountedSystem& system) { return make_sized<Euler>(system.size(), system); }),
      // |1 + h lambda| <= 1 at lambda = -a + i sqrt(w^2 - a^2), |lambda| = w: h < 2 a / w^2, none at all undamped
      .stability = {.R = [](std::complex<double> z) { return 1.0 + z; },
                    .oscillator_dt = [](double omega, double damping) { return 2 * damping / (omega * omega); }},
  });
}

}  // namespace stepwise
