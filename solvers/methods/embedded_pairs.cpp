// tsitouras54, verner98: embedded Runge-Kutta pairs of our own, hand-written on the fixed-step path's terms
// (plain loops, nothing allocated, f called through the counted system, or inline where the model offers it
// as a kernel (solvers/inline_stepper.hpp), and nothing else per stage), with a
// PI step-size controller and dense output for output times and events.
//
// The stage sums are unrolled at compile time over the tableau's nonzero coefficients (a tableau is a type,
// solvers/tableaus/), so a 16-stage Verner step does only the multiplications its coefficients need.
#include "solvers/adaptive_step.hpp"
#include "solvers/fixed_step.hpp"
#include "solvers/inline_stepper.hpp"
#include "solvers/run_support.hpp"
#include "solvers/step_controller.hpp"
#include "solvers/tableaus/dense_weight.hpp"
#include "solvers/tableaus/tsitouras54.hpp"
#include "solvers/tableaus/verner98.hpp"

#include <algorithm>
#include <array>
#include <utility>

namespace stepwise {
namespace {

// the stages of one explicit Runge-Kutta step of tableau T on a state of N entries (0: any size); F: the
// model's f called inline (solvers/inline_stepper.hpp), or void: through the system
template <class T, int N, class F = void>
class Stages {
  static constexpr bool inline_f = !std::is_void_v<F>;

  // Size doubles inside the stepper where N is known (nothing allocated per run: a 1 us run's allocations were
  // a tenth of it), else a vector of the run's size
  template <int Size>
  using Buffer = std::conditional_t<(Size > 0), std::array<double, static_cast<size_t>(Size)>, Eigen::VectorXd>;
  template <int Size>
  static Buffer<Size> buffer(Eigen::Index n) {
    if constexpr (Size > 0) return {};
    else return Eigen::VectorXd(n);
  }

 public:
  explicit Stages(const CountedSystem& s, KernelOr<F> f = {})
      : system_(s), f_(f), n_(s.size()), k_(buffer<T::dense_stages * N>(T::dense_stages * n_)), tmp_(buffer<N>(n_)) {}

  // k_0 = f(t, y0) unless first-same-as-last left it from the previous step (reuse_first)
  STEPWISE_SCALAR_STORES void compute(double t, double h, const double* y0, bool reuse_first) {
    if (!reuse_first) evaluate(t, y0, 0);
    [&]<int... I>(std::integer_sequence<int, I...>) { (stage<I + 1>(t, h, y0), ...); }(std::make_integer_sequence<int, T::stages - 1>{});
  }

  // y1 = y0 + h sum b_i k_i, and the error estimate's max over entries of |h sum e_i k_i| / (atol + rtol max(|y0|, |y1|))
  // (+inf where y1 is not finite); at a fixed step, where no estimate is wanted, |y1|inf instead, measured on
  // the way for the loop's divergence test
  template <bool estimate = true>
  STEPWISE_SCALAR_STORES double finish(double h, const double* y0, double* y1, double rtol = 0, double atol = 1) const {
    double worst = 0;
    RunningNorm norm;
    each_entry([&](Eigen::Index i) __attribute__((always_inline)) {
      const double v = y0[i] + h * weighted<Row::b>(i);
      y1[i] = v;
      if constexpr (estimate) worst = std::max(worst, std::abs(h * weighted<Row::e>(i)) / (atol + rtol * std::max(std::abs(y0[i]), std::abs(v))));
      norm.add(v);
    });
    if constexpr (!estimate) return norm.value();
    return std::isfinite(norm.value()) ? worst : std::numeric_limits<double>::infinity();
  }

  // the interpolant's own stages, after the step's (where T::dense_stages > T::stages): k_i = f(t0 + c_i h,
  // y0 + h sum_j a_ij k_j) over the step's stages and the ones before it
  void extend(double t, double h, const double* y0) {
    [&]<int... I>(std::integer_sequence<int, I...>) { (stage<T::stages + I>(t, h, y0), ...); }(std::make_integer_sequence<int, T::dense_stages - T::stages>{});
  }

  // y(t0 + theta h) from the last step's stages, the interpolant's own included (extend)
  void interpolate(double theta, double h, const double* y0, double* out) const {
    std::array<double, T::dense_stages> w{};
    for (int s = 0; s < T::dense_stages; ++s) w[static_cast<size_t>(s)] = tableau::dense_weight<T>(s, theta);
    for (Eigen::Index i = 0; i < size(); ++i) {
      double sum = 0;
      for (int s = 0; s < T::dense_stages; ++s) sum += w[static_cast<size_t>(s)] * k(s)[i];
      out[i] = y0[i] + h * sum;
    }
  }

  // first same as last: the last stage is f at the step's end, the next step's first (the two trade places,
  // so that the step's own first stage can be put back for its interpolant)
  void carry_last() {
    double *first = k(0), *last = k(T::stages - 1);
    for (Eigen::Index i = 0; i < size(); ++i) std::swap(first[i], last[i]);
  }

 private:
  Eigen::Index size() const { return N > 0 ? N : n_; }

  // body(i) for each entry of the state: with N known, written out entry by entry at compile time, not as a
  // loop. The loop vectoriser turned a 2-entry loop into one 16-byte operation whose store the next stage read
  // back 8 bytes at a time, and whose 16-byte loads of a stage written 8 bytes at a time, both missing
  // store-to-load forwarding on the chain from one stage's f to the next (verner98 on the pendulum: see
  // docs/performance.md); STEPWISE_SCALAR_STORES keeps the written-out entries apart
  template <class Body>
  void each_entry(const Body& body) const {
    if constexpr (N > 0) {
      [&]<int... I>(std::integer_sequence<int, I...>) { (body(Eigen::Index{I}), ...); }(std::make_integer_sequence<int, N>{});
    } else {
      for (Eigen::Index i = 0; i < n_; ++i) body(i);
    }
  }

  // which of the tableau's coefficient rows a sum takes: row I of a, b or e
  enum class Row { a, b, e };
  template <Row R, int I>
  static constexpr double coefficient(int j) {
    if constexpr (R == Row::a) return T::a[I][j];
    else if constexpr (R == Row::b) return T::b[j];
    else return T::e[j];
  }

  // sum_j coefficient_j k_j[i] over the first Count stages, the zero coefficients left out at compile time
  template <Row R, int I = 0, int Count = T::stages>
  double weighted(Eigen::Index i) const {
    double sum = 0;
    [&]<int... J>(std::integer_sequence<int, J...>) {
      const auto term = [&]<int Jc>() {
        if constexpr (coefficient<R, I>(Jc) != 0) sum += coefficient<R, I>(Jc) * k(Jc)[i];
      };
      (term.template operator()<J>(), ...);
    }(std::make_integer_sequence<int, Count>{});
    return sum;
  }

  template <int I>
  void stage(double t, double h, const double* y0) {
    double* tmp = tmp_.data();
    each_entry([&](Eigen::Index i) __attribute__((always_inline)) { tmp[i] = y0[i] + h * weighted<Row::a, I, I>(i); });
    evaluate(t + T::c[I] * h, tmp, I);
  }

  // k_j = f(t, y), y the step's start or the stage's argument (tmp_), counted either way. Inlined into each stage,
  // so that an inline f not seen by the compiler (a scene's compiled equations) gets the stage's values from the
  // registers that computed them rather than from their stores (verner98 on the written pendulum: 1.13-1.23 times
  // the built-in model out of line)
  __attribute__((always_inline)) void evaluate(double t, const double* y, int j) {
    if constexpr (inline_f) {
      ++system_.stats().rhs_evals;
      f_(t, y, k(j));
    } else if (y == tmp_.data()) {
      system_.rhs(t, stage_, stage_out(j));
    } else {
      system_.rhs(t, Eigen::Map<const Eigen::VectorXd>(y, n_), stage_out(j));
    }
  }

  // stage j's values: one block of the stages' buffer (with N known, at a fixed offset from one pointer)
  double* k(int j) { return k_.data() + j * size(); }
  const double* k(int j) const { return k_.data() + j * size(); }
  Eigen::Map<Eigen::VectorXd> stage_out(int j) { return {k(j), size()}; }

  const CountedSystem& system_;
  [[no_unique_address]] KernelOr<F> f_;
  Eigen::Index n_;
  Buffer<T::dense_stages * N> k_;  // the stages, one after another
  Buffer<N> tmp_;                  // a stage's argument
  const Eigen::Ref<const Eigen::VectorXd> stage_{Eigen::Map<const Eigen::VectorXd>(tmp_.data(), n_)};
};

// the pair at a fixed step (for the order tests and fixed-step sweeps): no error estimate used
template <class T>
struct FixedPair {
  template <int N, class F>
  class Stepper final : public FixedStepper {
   public:
    explicit Stepper(const CountedSystem& s, KernelOr<F> f = {}) : stages_(s, f) {}
    bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
      stages_.compute(t, h, y.data(), false);
      norm_ = stages_.template finish<false>(h, y.data(), y_next.data());
      return true;
    }

   private:
    Stages<T, N, F> stages_;
  };
};

// the pair with its error estimate, the PI controller of step_controller.hpp and dense output
template <class T>
struct AdaptivePair {
  template <int N, class F>
  class Stepper final : public AdaptiveStepper {
   public:
    Stepper(const CountedSystem& s, const StepControl& control, const std::string& name, KernelOr<F> f = {})
        : stages_(s, f), rtol_(control.rtol), atol_(control.atol), y1_(s.size()), name_(name) {}

    bool step(double& t, double t_limit, double& h, Eigen::VectorXd& y, long& rejected, std::string& failure) override {
      for (;;) {
        const bool clamped = t + h >= t_limit;
        const double dt = clamped ? t_limit - t : h;
        stages_.compute(t, dt, y.data(), have_first_);
        have_first_ = true;  // a retry from the same (t, y) reuses k_0
        carried_ = extended_ = false;
        const double err = stages_.finish(dt, y.data(), y1_.data(), rtol_, atol_);
        if (err <= 1) {
          last_t_ = t;
          last_h_ = dt;
          t = clamped ? t_limit : t + dt;
          y.swap(y1_);  // y1_ keeps the step's start, for dense output
          if constexpr (T::fsal) {
            stages_.carry_last();
            carried_ = true;
          } else {
            have_first_ = false;
          }
          h = controller_.next_after_accepted(err, dt, h, clamped);
          return true;
        }
        ++rejected;
        if (!controller_.retry_after_rejected(err, dt, t, h, name_, failure)) return false;
      }
    }

    bool dense() const override { return true; }
    void interpolate(double t, Eigen::VectorXd& out) override {
      out.resize(y1_.size());
      ready_interpolant();
      stages_.interpolate((t - last_t_) / last_h_, last_h_, y1_.data(), out.data());
    }

    bool restep(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_out) override {
      // within the last accepted step from its start: the interpolant
      if (t == last_t_ && h <= last_h_ && y == y1_) {
        y_out.resize(y.size());
        ready_interpolant();
        stages_.interpolate(h / last_h_, last_h_, y1_.data(), y_out.data());
        return true;
      }
      have_first_ = carried_ = extended_ = false;
      y_out.resize(y.size());
      stages_.compute(t, h, y.data(), false);
      return std::isfinite(stages_.finish(h, y.data(), y_out.data(), rtol_, atol_));
    }

    // the state changed (an event): k_0 is no longer f there; the last step's stages stay for its interpolant
    void reset() override {
      have_first_ = false;
      controller_.reset();
    }

   private:
    // the last step's stages as its interpolant wants them: the first back in place (carry_last moved it;
    // the next step then computes its first stage afresh), and the interpolant's own stages, computed once
    // a step and only for a step that has an output time or an event inside it
    void ready_interpolant() {
      if (carried_) {
        stages_.carry_last();
        carried_ = have_first_ = false;
      }
      if constexpr (T::dense_stages > T::stages) {
        if (!extended_) stages_.extend(last_t_, last_h_, y1_.data());
        extended_ = true;
      }
    }

    Stages<T, N, F> stages_;
    double rtol_, atol_;
    Eigen::VectorXd y1_;
    std::string name_;
    bool have_first_ = false;  // k_0 holds f at the current (t, y): a rejected try's, or first same as last
    bool carried_ = false;     // the last step's first and last stages trade places for the latter
    bool extended_ = false;    // the interpolant's own stages are the last step's
    PiStepController controller_{T::estimate_order + 1};
    double last_t_ = 0, last_h_ = 0;
  };
};

template <class T>
MakeIntegrator pair_integrator() {
  return [](const Method& method, const StepControl& control) -> std::unique_ptr<Integrator> {
    if (control.dt)
      return std::make_unique<FixedStepIntegrator>(method, control, [](const CountedSystem& s) {
        return make_inline_or_sized<FixedPair<T>::template Stepper>(s);
      });
    return std::make_unique<AdaptiveStepIntegrator>(method, control, [name = std::string(method.name)](const CountedSystem& s, const StepControl& c) {
      return make_inline_or_sized<AdaptivePair<T>::template Stepper, AdaptiveStepper>(s, c, name);
    });
  };
}

}  // namespace

void register_embedded_pairs_methods(MethodTable& table) {
  table.add({.name = "tsitouras54",
             .family = Family::embedded_pairs,
             .source = Source::hand_written,
             .description = "Tsitouras 5(4), 7 stages FSAL, PI control, 4th-order dense output",
             .order = {5, 5, "5"},
             .stepping = Stepping::fixed_or_adaptive,
             .make = pair_integrator<tableau::Tsitouras54>()});
  table.add({.name = "verner98",
             .family = Family::embedded_pairs,
             .source = Source::hand_written,
             .description = "Verner's most efficient 9(8), 16 stages, PI control, 8th-order dense output (5 more stages)",
             .order = {9, 9, "9"},
             .stepping = Stepping::fixed_or_adaptive,
             .make = pair_integrator<tableau::Verner98>()});
}

}  // namespace stepwise
