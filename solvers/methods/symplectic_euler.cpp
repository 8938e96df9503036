// symplectic-euler: semi-implicit Euler on y = (x, v), the velocity first.
#include "solvers/inline_stepper.hpp"
#include "solvers/stability.hpp"
#include "solvers/wave_step.hpp"

#include <algorithm>
#include <limits>

namespace stepwise {
namespace {

// the method at one coordinate: v1 = v0 + h a, then x1 = x0 + h v1
inline void kick_drift(double h, double x0, double v0, double a, double& x1, double& v1) {
  v1 = v0 + h * a;
  x1 = x0 + h * v1;
}

// semi-implicit (symplectic) Euler on y = (x, v): v1 = v0 + h a(t0, x0, v0), x1 = x0 + h v1.
// Memory-bound on large systems (a particle system): after the acceleration, one pass over the state does
// both updates and the divergence norm; with a local acceleration the whole step is one pass, block by
// block, the block's acceleration never leaving cache
class SymplecticEuler final : public PlainStepping<SymplecticEuler> {
 public:
  static constexpr int size = 0;  // PlainStepping: no advance(), the state of a run-time size

  explicit SymplecticEuler(const CountedSystem& s)
      : system_(s), view_(*s.as<SecondOrderView>()), n_(view_.positions), a_(view_.local_acceleration ? std::min(block, n_) : n_) {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    const double* x0 = y.data();
    const double* v0 = x0 + n_;
    double* x1 = y_next.data();
    double* v1 = x1 + n_;
    Sweep sweep;
    const bool local = static_cast<bool>(view_.local_acceleration);
    if (local) ++system_.stats().rhs_evals;
    else second_order_acceleration(system_, view_, t, y, a_, f_);
    for (Eigen::Index first = 0; first < n_; first += block) {
      const Eigen::Index count = std::min(block, n_ - first);
      const double* a = a_.data() + first;
      if (local) {
        view_.local_acceleration(t, x0 + first, v0 + first, a_.data(), first, count);
        a = a_.data();
      }
      sweep.update(h, x0 + first, v0 + first, a, x1 + first, v1 + first, count);
    }
    norm_ = sweep.bad ? std::numeric_limits<double>::infinity() : sweep.largest;
    return true;
  }

 private:
  // entries per block: 3 x 8 KiB of x, v and a, well inside L1 and L2
  static constexpr Eigen::Index block = 1024;

  // v1 = v0 + h a, x1 = x0 + h v1 over a block, then |y_next|inf of the block while it is in cache (in
  // the update loop itself the max would stop it from vectorising: a NaN-exact max has no vector form)
  struct Sweep {
    double largest = 0;
    bool bad = false;  // some entry is inf or NaN
    // built twice, for AVX2 and for plain x86-64, the one chosen at load time (the same IEEE operations in
    // either, without fused multiply-adds, so the same bits); clang 15 leaves the Eigen calls of an AVX2
    // clone unresolved at link time, so its builds (the fuzz preset) take the one plain version
#if defined(__clang__)
#define STEPWISE_CLONES
#else
#define STEPWISE_CLONES __attribute__((target_clones("avx2", "default")))
#endif
    STEPWISE_CLONES void update(double h, const double* __restrict x0, const double* __restrict v0, const double* __restrict a,
                double* __restrict x1, double* __restrict v1, Eigen::Index n) {
      for (Eigen::Index i = 0; i < n; ++i) kick_drift(h, x0[i], v0[i], a[i], x1[i], v1[i]);
      // x - x is 0 for a finite entry and NaN otherwise, so the sums are 0 exactly when all are finite
      // (Eigen vectorises sums and plain maxima; its allFinite() and NaN-propagating max measured slower)
      const Eigen::Map<const Eigen::ArrayXd> x(x1, n), v(v1, n);
      if (!((x - x).sum() == 0 && (v - v).sum() == 0)) bad = true;
      else largest = std::max({largest, x.abs().maxCoeff(), v.abs().maxCoeff()});
    }
  };

  const CountedSystem& system_;
  const SecondOrderView& view_;
  Eigen::Index n_;
  Eigen::VectorXd a_, f_;  // f_: f where the model has no acceleration of its own
};

// the same on the model's f called inline (solvers/inline_stepper.hpp), a = its second half: on a small state
// (the pendulum) the whole step in registers
template <int N, class F>
class InlineSymplecticEuler final : public PlainStepping<InlineSymplecticEuler<N, F>> {
  using FixedStepper::norm_;

 public:
  static constexpr int size = N;  // PlainStepping: advance() offered

  InlineSymplecticEuler(const CountedSystem& s, F kernel) : system_(s), kernel_(kernel) {}
  STEPWISE_SCALAR_STORES bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    counted(1);
    norm_ = advance(t, h, y.data(), y_next.data());
    return true;
  }
  double advance(double t, double h, const double* y0, double* y1) const {
    constexpr int n = N / 2;
    std::array<double, N> f;
    kernel_(t, y0, f.data());
    RunningNorm norm;
    for (int i = 0; i < n; ++i) {
      kick_drift(h, y0[i], y0[n + i], f[n + i], y1[i], y1[n + i]);
      norm.add(y1[i]);
      norm.add(y1[n + i]);
    }
    return norm.value();
  }
  void counted(long steps) const { system_.stats().rhs_evals += steps; }

 private:
  const CountedSystem& system_;
  F kernel_;
};

template <int N, class F>
using Stepper = std::conditional_t<std::is_void_v<F>, SymplecticEuler, InlineSymplecticEuler<N, F>>;

}  // namespace

void register_symplectic_euler_methods(MethodTable& table) {
  table.add({
      .name = "symplectic-euler",
      .family = Family::symplectic_euler,
      .source = Source::hand_written,
      .description = "semi-implicit, fixed step",
      .order = {1, 1, "1"},
      .stepping = Stepping::fixed,
      .needs = needs_second_order,
      .make = fixed_steps([](const CountedSystem& system) { return make_inline_or_sized<Stepper>(system); }),
      .stability = {.oscillator_dt = symplectic_euler_oscillator_dt, .wave_dt = symplectic_euler_wave_dt},
  });
}

}  // namespace stepwise
