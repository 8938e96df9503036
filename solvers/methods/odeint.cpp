// odeint-rk4, odeint-dopri5, odeint-rkf78, odeint-bulirsch-stoer: Boost.Odeint's steppers, the library a
// C++ user would pick instead, on an Eigen state (odeint's vector-space algebra), every call of f through
// the counted system like every other method's. Fixed steps run in the shared fixed-step loop, controlled
// steps in the shared adaptive loop (outputs, events, projection and divergence as for every method).
#include "solvers/adaptive_step.hpp"
#include "solvers/fixed_step.hpp"
#include "solvers/run_support.hpp"

#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>

namespace stepwise {
namespace {

namespace odeint = boost::numeric::odeint;
using State = Eigen::VectorXd;

// odeint's system: f through the counted wrapper
struct Rhs {
  const CountedSystem* system;
  void operator()(const State& y, State& dydt, double t) const { system->rhs(t, y, dydt); }
};

// one of odeint's error-free steppers at a fixed step, out of place
template <class Stepper>
class OdeintFixed final : public FixedStepper {
 public:
  explicit OdeintFixed(const CountedSystem& s) : rhs_{&s} {}
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    stepper_.do_step(rhs_, y, t, y_next, h);
    return true;
  }
  // a first-same-as-last stepper (dopri5) keeps f at the step's end: stale after an event moved the state
  void reset() override {
    if constexpr (requires { stepper_.reset(); }) stepper_.reset();
  }

 private:
  Rhs rhs_;
  Stepper stepper_;
};

// odeint's controlled steppers (and Bulirsch-Stoer): try_step until one is accepted, within t_limit
template <class Controlled, class Plain>
class OdeintControlled final : public AdaptiveStepper {
 public:
  OdeintControlled(const CountedSystem& s, Controlled controlled, std::string method)
      : rhs_{&s}, controlled_(std::move(controlled)), method_(std::move(method)) {}
  bool step(double& t, double t_limit, double& h, Eigen::VectorXd& y, long& rejected, std::string& failure) override {
    // odeint's controllers give up after 500 rejections in a row, as a run that cannot go on
    for (int trial = 0; trial < 500; ++trial) {
      const bool clamped = t + h >= t_limit;
      double dt = clamped ? t_limit - t : h;
      const double t_before = t;
      if (controlled_.try_step(rhs_, y, t, dt) == odeint::success) {
        if (clamped) t = t_limit;  // land on the output time exactly, not a rounding away
        // the controller's next proposal; a step cut short to land on an output keeps the trial step
        h = clamped ? std::max(h, dt) : dt;
        return y.allFinite();
      }
      ++rejected;
      h = dt;
      if (!(h > 1e-14 * std::max(1.0, std::abs(t_before)))) break;
    }
    failure = fmt::format("{}: try_step rejected every step down to h = {:.3g} at t = {:.9g}", method_, h, t);
    return false;
  }
  bool restep(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_out) override {
    // a first-same-as-last stepper keeps f at its last step's end: from another state, stale
    if constexpr (requires { plain_.reset(); }) plain_.reset();
    plain_.do_step(rhs_, y, t, y_out, h);
    return true;
  }
  void reset() override {
    if constexpr (requires { controlled_.reset(); }) controlled_.reset();
    if constexpr (requires { plain_.reset(); }) plain_.reset();
  }

 private:
  Rhs rhs_;
  Controlled controlled_;
  Plain plain_;
  std::string method_;
};

using Dopri5 = odeint::runge_kutta_dopri5<State, double, State, double, odeint::vector_space_algebra>;
using Rkf78 = odeint::runge_kutta_fehlberg78<State, double, State, double, odeint::vector_space_algebra>;
using Rk4 = odeint::runge_kutta4<State, double, State, double, odeint::vector_space_algebra>;
using BulirschStoer = odeint::bulirsch_stoer<State, double, State, double, odeint::vector_space_algebra>;

// a fixed step with the stepper alone, or its controlled form to rtol/atol
template <class Stepper>
MakeIntegrator odeint_integrator() {
  return [](const Method& method, const StepControl& control) -> std::unique_ptr<Integrator> {
    if (control.dt)
      return std::make_unique<FixedStepIntegrator>(method, control, [](const CountedSystem& s) { return std::make_unique<OdeintFixed<Stepper>>(s); });
    return std::make_unique<AdaptiveStepIntegrator>(method, control, [name = std::string(method.name)](const CountedSystem& s, const StepControl& c) {
      auto controlled = odeint::make_controlled(c.atol, c.rtol, Stepper());
      return std::make_unique<OdeintControlled<decltype(controlled), Stepper>>(s, std::move(controlled), name);
    });
  };
}

// Bulirsch-Stoer's own control; restepping for an event uses its modified midpoint at eight substeps
MakeIntegrator bulirsch_stoer_integrator() {
  return [](const Method& method, const StepControl& control) -> std::unique_ptr<Integrator> {
    return std::make_unique<AdaptiveStepIntegrator>(method, control, [name = std::string(method.name)](const CountedSystem& s, const StepControl& c) {
      using Plain = odeint::modified_midpoint<State, double, State, double, odeint::vector_space_algebra>;
      return std::make_unique<OdeintControlled<BulirschStoer, Plain>>(s, BulirschStoer(c.atol, c.rtol), name);
    });
  };
}

}  // namespace

void register_odeint_methods(MethodTable& table) {
  table.add({.name = "odeint-rk4",
             .family = Family::odeint,
             .source = Source::odeint,
             .description = "classical Runge-Kutta 4, fixed step",
             .order = {4, 4, "4"},
             .stepping = Stepping::fixed,
             .make = fixed_steps([](const CountedSystem& s) { return std::make_unique<OdeintFixed<Rk4>>(s); })});
  table.add({.name = "odeint-dopri5",
             .family = Family::odeint,
             .source = Source::odeint,
             .description = "Dormand-Prince 5(4), controlled or fixed step",
             .order = {5, 5, "5"},
             .stepping = Stepping::fixed_or_adaptive,
             .make = odeint_integrator<Dopri5>()});
  table.add({.name = "odeint-rkf78",
             .family = Family::odeint,
             .source = Source::odeint,
             .description = "Runge-Kutta-Fehlberg 7(8), controlled or fixed step",
             .order = {8, 8, "8"},
             .stepping = Stepping::fixed_or_adaptive,
             .make = odeint_integrator<Rkf78>()});
  table.add({.name = "odeint-bulirsch-stoer",
             .family = Family::odeint,
             .source = Source::odeint,
             .description = "Bulirsch-Stoer extrapolation, adaptive order and step",
             .order = {2, 16, "variable"},
             .stepping = Stepping::adaptive,
             .make = bulirsch_stoer_integrator()});
}

}  // namespace stepwise
