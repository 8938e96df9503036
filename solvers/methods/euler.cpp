// euler: explicit Euler, the first method the seeds teach.
#include "solvers/fixed_step.hpp"
#include "solvers/run_support.hpp"

namespace stepwise {
namespace {

// y1 = y0 + h f(t0, y0)
class Euler final : public FixedStepper {
 public:
  explicit Euler(const CountedSystem& s) : system_(s), f_(s.size()) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    system_.rhs(t, y, f_);
    y_next = y + h * f_;
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
      .make = fixed_steps([](const CountedSystem& system) { return std::make_unique<Euler>(system); }),
      // |1 + h lambda| <= 1 at lambda = -a + i sqrt(w^2 - a^2), |lambda| = w: h < 2 a / w^2, none at all undamped
      .stability = {.R = [](std::complex<double> z) { return 1.0 + z; },
                    .oscillator_dt = [](double omega, double damping) { return 2 * damping / (omega * omega); }},
  });
}

}  // namespace stepwise
