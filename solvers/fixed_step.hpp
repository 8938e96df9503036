// Fixed-step integration: one loop over the step grid, shared by hand-written, GSL and GPU steppers.
#pragma once

#include <stepwise/solvers/method.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace stepwise {

class CountedSystem;

// one method's step y(t) -> y(t + h); made once per run, so it may keep state (multistep history)
class FixedStepper {
 public:
  virtual ~FixedStepper() = default;
  // y_next = y(t + h) from y = y(t) (two buffers, so the loop keeps the step's start without a copy); on
  // failure return false and say which call failed in `failure`
  virtual bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) = 0;
  // |y_next|inf of the last step, +inf if any entry is not finite, when the stepper measured it on its way
  // through the state (set by step(), read without a virtual call): the loop's divergence test then needs
  // no pass of its own
  std::optional<double> last_norm() const { return norm_ >= 0 ? std::optional(norm_) : std::nullopt; }
  // events the step handled itself (a contact method's impacts), as summary.json writes them ("impact"),
  // since the last call: the loop records them at the step's end
  virtual void take_events(std::vector<std::string>& kinds) { kinds.clear(); }
  // whether take_events can ever report any: the loop asks once, and not at every step when not
  virtual bool handles_events() const { return false; }
  // forget any history: the next step starts afresh (after an event changed the state, or to re-step)
  virtual void reset() {}
  // |y|inf of a state this stepper steps: the whole state's, or for a stepper on one rank's part of it
  // (solvers/distributed_wave.hpp) the whole grid's over the ranks, so they agree on the divergence bound
  virtual double norm(const Eigen::VectorXd& y) const { return y.lpNorm<Eigen::Infinity>(); }
  // the loop's full steps taken by the stepper itself, without a virtual call a step (PlainStepping below):
  // asked only of a run without events, projection or the method's own events. 0: not offered
  virtual long plain_steps(double& /*t*/, double /*dt*/, double /*target*/, double /*snap*/, double /*bound*/, Eigen::VectorXd& /*y*/,
                           Eigen::VectorXd& /*y_next*/, bool& /*diverged*/) {
    return 0;
  }

 protected:
  double norm_ = -1;  // step()'s measure of |y_next|inf; negative: not measured
};

// on a stepper's step(): no pairing of a small state's scalar stores into vector stores: f reading y[1] right
// after a stage wrote y[0..1] as one 16-byte store misses store-to-load forwarding (on x86-64 cores such as AMD
// EPYC), a stall on the chain from one stage's f to the next. Loops over large states are still
// vectorised (that is the loop vectoriser, not this one). GCC's attribute: clang (the fuzz build) has none
// such, and warned at every use
#if defined(__clang__)
#define STEPWISE_SCALAR_STORES
#else
#define STEPWISE_SCALAR_STORES __attribute__((optimize("no-tree-slp-vectorize")))
#endif

// the same stepper built for a state of N entries known at compile time (its loops unrolled: on a pendulum
// the loop bookkeeping would otherwise cost as much as the method's arithmetic), or for any size (N = 0)
template <template <int> class Stepper, class Base = FixedStepper, class... Args>
std::unique_ptr<Base> make_sized(Eigen::Index n, Args&&... args) {
  switch (n) {
    case 2: return std::make_unique<Stepper<2>>(std::forward<Args>(args)...);
    case 3: return std::make_unique<Stepper<3>>(std::forward<Args>(args)...);
    case 4: return std::make_unique<Stepper<4>>(std::forward<Args>(args)...);
    case 6: return std::make_unique<Stepper<6>>(std::forward<Args>(args)...);
    default: return std::make_unique<Stepper<0>>(std::forward<Args>(args)...);
  }
}

// |y|inf of the entries a stepper writes, folded in as it writes them (the loop's divergence test then needs
// no pass of its own); +inf once any entry is inf or NaN (v - v is 0 exactly for a finite v)
class RunningNorm {
 public:
  void add(double v) {
    largest_ = std::max(largest_, std::abs(v));
    nonfinite_ += v - v;
  }
  double value() const { return nonfinite_ == 0 ? largest_ : std::numeric_limits<double>::infinity(); }

 private:
  double largest_ = 0, nonfinite_ = 0;
};

// the end of a step from t: t + dt, or the output time when that is within `snap` of it (no sliver left)
inline double step_end(double t, double dt, double target, double snap) { return (target - (t + dt) <= snap) ? target : t + dt; }

// the base of a stepper that never fails and measures its norm on every step (last_norm), Self: that
// stepper, final: it takes the loop's full steps itself, step() called directly (inline), as the loop takes
// them (h = (t + dt) - t, y and y_next swapped) while a step ends short of `target`; the landing step is the
// loop's. Returns the steps taken, t at the last one's end; after a step past `bound`, `diverged`, that step
// counted, t at its start and y_next its end.
//
// A stepper on the model's f inline with a state of known size (Self::size > 0) offers advance(t, h, y0, y1):
// the step on raw states, returning |y1|inf, f's calls not counted (counted(steps) counts them). The run then
// keeps the state in local arrays, which the compiler keeps in registers, instead of the two vectors' memory:
// no store and reload of the state, and of their data pointers after a swap, on the chain from one step's f to
// the next's (euler on the pendulum: 1.36-1.41 -> 1.17-1.29 times odeint's std::array loop, docs/performance.md).
// There the divergence test is taken on every `test_every`-th state, not every one: a block of steps runs with
// no test (the norm advance() returns is unused, and computed not at all once inlined), then its last state is
// tested; past the bound, or not finite, the block is stepped again from its start (kept), testing each state,
// so the blow-up is reported at the same step, the same time and the same state as a test at every step
// reports it. The one difference: a state past the bound inside a block whose last state is back within it is
// not caught (a swing past 10^12 |y0| and back within a block's steps, which no blow-up does: NaN and inf stay,
// and a growth by 10^12 does not undo itself in 16 steps). Its cost: the norm's few flops a step had been 0.15
// of euler's 1.2-1.3 times odeint's loop on the pendulum, which is now 0.99-1.01 (docs/performance.md)
template <class Self>
class PlainStepping : public FixedStepper {
 public:
  static constexpr long test_every = 16;  // steps a block (the sized path)

  // (with the steppers' own optimisation options, so that their step() can be inlined here)
  STEPWISE_SCALAR_STORES long plain_steps(double& t, double dt, double target, double snap, double bound, Eigen::VectorXd& y,
                                          Eigen::VectorXd& y_next, bool& diverged) final {
    Self& self = static_cast<Self&>(*this);
    long taken = 0;
    if constexpr (Self::size > 0) {
      constexpr int n = Self::size;
      std::array<double, n> y0, y1, start;
      std::copy_n(y.data(), n, y0.begin());
      double t0 = t;
      for (bool more = true; more;) {
        // a block of up to test_every steps, untested
        start = y0;
        const double t_start = t0;
        long block = 0;
        while (block < test_every && (more = step_end(t0, dt, target, snap) != target)) {
          const double t1 = t0 + dt;
          self.advance(t0, t1 - t0, y0.data(), y1.data());
          ++block;
          t0 = t1;
          y0 = y1;
        }
        RunningNorm last;
        for (const double v : y0) last.add(v);
        if (last.value() <= bound) [[likely]] {
          taken += block;
          continue;
        }
        // past the bound by the block's end: the block again from its start, each state tested
        y0 = start;
        t0 = t_start;
        for (long i = 0; i < block; ++i) {
          const double t1 = t0 + dt;
          const double norm = self.advance(t0, t1 - t0, y0.data(), y1.data());
          ++taken;
          if (!(norm <= bound)) {
            diverged = true;
            norm_ = norm;
            std::copy_n(y1.begin(), n, y_next.data());
            break;
          }
          t0 = t1;
          y0 = y1;
        }
        break;
      }
      t = t0;
      std::copy_n(y0.begin(), n, y.data());
      self.counted(taken);
    } else {
      std::string unused;
      while (step_end(t, dt, target, snap) != target) {
        const double t_next = t + dt;
        self.step(t, t_next - t, y, y_next, unused);
        ++taken;
        if (!(norm_ <= bound)) [[unlikely]] {
          diverged = true;
          return taken;
        }
        t = t_next;
        y.swap(y_next);
      }
    }
    return taken;
  }
};

using FixedStepperFactory = std::function<std::unique_ptr<FixedStepper>(const CountedSystem& system)>;

// steps of exactly dt, the last one before each output time shortened to land on it
class FixedStepIntegrator final : public Integrator {
 public:
  // `method` is the table's entry (it outlives every run); BadMethod from integrate() for a system without
  // the structure the method needs
  FixedStepIntegrator(const Method& method, StepControl control, FixedStepperFactory make_stepper)
      : method_(method), control_(control), make_stepper_(std::move(make_stepper)) {}
  RunResult solve(const OdeSystem& system, double t0, const Eigen::VectorXd& y0,
                      std::span<const double> t_out) const override;

 private:
  const Method& method_;
  StepControl control_;
  FixedStepperFactory make_stepper_;
};

// a fixed-step method's MakeIntegrator (method.hpp): the loop above around the steps `make_stepper` makes
MakeIntegrator fixed_steps(FixedStepperFactory make_stepper);

}  // namespace stepwise
