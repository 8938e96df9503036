// gsl-*: every GSL odeiv2 stepper, fixed step or adaptive (GSL's types stay in this file).
//
// Pitfalls with GSL 2.7 handled here:
// - rk1imp, rk2imp, rk4imp, bsimp and msbdf dereference the Jacobian: a NULL one segfaults, so the
//   system's analytic Jacobian or a central finite-difference one is always supplied;
// - gsl_odeiv2_driver_apply_fixed_step still runs the error control and can reject a step: fixed-step
//   runs call gsl_odeiv2_step_apply directly, through the shared fixed-step loop;
// - msadams and msbdf need their driver (they read the control's error level), so a driver is always allocated;
// - GSL's default error handler aborts the process: it is switched off once, and return codes are reported.
#include "solvers/events.hpp"
#include "solvers/fd_jacobian.hpp"
#include "solvers/adaptive_step.hpp"
#include "solvers/fixed_step.hpp"
#include "solvers/run_support.hpp"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include <mutex>

namespace stepwise {
namespace {

void switch_off_abort_handler() {
  static std::once_flag once;
  std::call_once(once, [] { gsl_set_error_handler_off(); });
}

// what GSL's C callbacks reach through their void* parameter
struct GslCallbacks {
  const CountedSystem* system;
  int n;                       // system->size(), read once: the RHS callback is the hot path
  Eigen::MatrixXd jac;         // df/dy (n x n), column-major scratch, allocated by the first Jacobian call:
                               // explicit steppers never make one, so they run systems too large for it
  Eigen::VectorXd fp, fm;      // scratch for df/dt
};

int gsl_rhs(double t, const double y[], double dydt[], void* params) {
  const auto& c = *static_cast<GslCallbacks*>(params);
  const int n = c.n;
  Eigen::Map<Eigen::VectorXd> out(dydt, n);
  // counted here and the inner system called directly: one virtual call per evaluation, not two
  ++c.system->stats().rhs_evals;
  c.system->inner().rhs(t, Eigen::Map<const Eigen::VectorXd>(y, n), out);
  // a non-finite derivative is caught after the step by the divergence test, not here on every call
  return GSL_SUCCESS;
}

// dfdy is row-major n x n; dfdt by central differences in t unless the system is autonomous
int gsl_jacobian(double t, const double y[], double* dfdy, double dfdt[], void* params) {
  auto& c = *static_cast<GslCallbacks*>(params);
  const int n = c.system->size();
  Eigen::Map<const Eigen::VectorXd> ym(y, n);
  c.jac.resize(n, n);
  jacobian_or_fd(*c.system, t, ym, c.jac);
  ++c.system->stats().jac_evals;
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(dfdy, n, n) = c.jac;
  Eigen::Map<Eigen::VectorXd> ft(dfdt, n);
  if (c.system->autonomous()) {
    ft.setZero();
  } else {
    const double d = std::cbrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(t));
    c.system->rhs(t + d, ym, c.fp);
    c.system->rhs(t - d, ym, c.fm);
    ft = (c.fp - c.fm) / (2 * d);
  }
  return c.jac.allFinite() ? GSL_SUCCESS : GSL_EBADFUNC;
}

// owns the GSL system, its callbacks and a driver (which owns stepper, control and evolve)
class GslSession {
 public:
  GslSession(const CountedSystem& system, const gsl_odeiv2_step_type* type, double h0, const StepControl& control)
      : callbacks_{&system, system.size(), Eigen::MatrixXd(), Eigen::VectorXd(system.size()),
                   Eigen::VectorXd(system.size())},
        sys_{gsl_rhs, gsl_jacobian, static_cast<size_t>(system.size()), &callbacks_},
        driver_(gsl_odeiv2_driver_alloc_y_new(&sys_, type, h0, control.atol, control.rtol)),
        yerr_(system.size()) {
    if (!driver_) throw std::runtime_error("gsl_odeiv2_driver_alloc_y_new returned NULL");
  }
  GslSession(const GslSession&) = delete;
  GslSession& operator=(const GslSession&) = delete;
  ~GslSession() { gsl_odeiv2_driver_free(driver_); }

  gsl_odeiv2_driver* driver() { return driver_; }
  const gsl_odeiv2_system* sys() const { return &sys_; }
  double* yerr() { return yerr_.data(); }

 private:
  GslCallbacks callbacks_;
  gsl_odeiv2_system sys_;
  gsl_odeiv2_driver* driver_;
  Eigen::VectorXd yerr_;
};

// one gsl_odeiv2_step_apply per step: no error control, so a fixed step is never rejected
class GslFixedStepper final : public FixedStepper {
 public:
  GslFixedStepper(const CountedSystem& system, std::string method, const gsl_odeiv2_step_type* type,
                  const StepControl& control)
      : session_(system, type, *control.dt, iteration_control(type, control)), method_(std::move(method)) {}

  // the implicit Runge-Kutta steppers solve their stage equations to the control's error level: at a fixed
  // step it must sit near round-off, or it, not dt, sets the error (rk4imp measured at order ~2 on the flow
  // field with the default 1e-6). msbdf's Newton iteration fails outright that tight, so the others keep it.
  static StepControl iteration_control(const gsl_odeiv2_step_type* type, StepControl control) {
    if (type == gsl_odeiv2_step_rk1imp || type == gsl_odeiv2_step_rk2imp || type == gsl_odeiv2_step_rk4imp) {
      control.rtol = 1e-13;
      control.atol = 1e-15;
    }
    return control;
  }
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) override {
    y_next = y;  // GSL steps in place
    const int code = gsl_odeiv2_step_apply(session_.driver()->s, t, h, y_next.data(), session_.yerr(), nullptr, nullptr,
                                           session_.sys());
    if (code == GSL_SUCCESS) return true;
    failure = fmt::format("{}: gsl_odeiv2_step_apply returned {} ({}) at t = {:.9g}", method_, code, gsl_strerror(code), t);
    return false;
  }
  void reset() override { gsl_odeiv2_step_reset(session_.driver()->s); }

 private:
  GslSession session_;
  std::string method_;
};

// gsl_odeiv2_evolve_apply, one accepted step a call, in the shared adaptive loop (adaptive_step.hpp)
class GslAdaptiveStepper final : public AdaptiveStepper {
 public:
  GslAdaptiveStepper(const CountedSystem& system, std::string method, const gsl_odeiv2_step_type* type, const StepControl& control, double h0)
      : session_(system, type, h0, control), method_(std::move(method)),
        multistep_(type == gsl_odeiv2_step_msadams || type == gsl_odeiv2_step_msbdf) {}
  bool step(double& t, double t_limit, double& h, Eigen::VectorXd& y, long& rejected, std::string& failure) override {
    if (history_spent_) reset();
    history_spent_ = false;
    gsl_odeiv2_driver* d = session_.driver();
    const unsigned long failed_before = d->e->failed_steps;
    const int code = gsl_odeiv2_evolve_apply(d->e, d->c, d->s, session_.sys(), &t, t_limit, &h, y.data());
    rejected += static_cast<long>(d->e->failed_steps - failed_before);
    if (code == GSL_SUCCESS) return true;
    // f produced a non-finite value: the run has blown up, which the loop reports as diverged
    if (code != GSL_EBADFUNC) failure = fmt::format("{}: gsl_odeiv2_evolve_apply returned {} ({}) at t = {:.9g}", method_, code, gsl_strerror(code), t);
    return false;
  }
  // a one-step method: one step of h from the start. A multistep one restarts at order 1, so one step would
  // place an event to first order: it is integrated to t + h under its own error control instead, which spends
  // its history (the next step() starts afresh)
  bool restep(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_out) override {
    gsl_odeiv2_driver* d = session_.driver();
    gsl_odeiv2_step_reset(d->s);
    y_out = y;
    if (!multistep_) return gsl_odeiv2_step_apply(d->s, t, h, y_out.data(), session_.yerr(), nullptr, nullptr, session_.sys()) == GSL_SUCCESS;
    history_spent_ = true;
    gsl_odeiv2_evolve_reset(d->e);
    double at = t, trial = h;
    while (at < t + h)
      if (gsl_odeiv2_evolve_apply(d->e, d->c, d->s, session_.sys(), &at, t + h, &trial, y_out.data()) != GSL_SUCCESS) return false;
    return true;
  }
  // a changed state (an event) invalidates the multistep history and the control's memory
  void reset() override {
    gsl_odeiv2_evolve_reset(session_.driver()->e);
    gsl_odeiv2_step_reset(session_.driver()->s);
  }

 private:
  GslSession session_;
  std::string method_;
  bool multistep_;
  bool history_spent_ = false;  // a restep integrated past the last step's history
};

// one integrator of GSL's stepper `type`: fixed step when control.dt is set, else adaptive to rtol/atol
MakeIntegrator gsl_integrator(const gsl_odeiv2_step_type* type) {
  return [type](const Method& method, const StepControl& control) -> std::unique_ptr<Integrator> {
    switch_off_abort_handler();
    if (!control.dt)
      return std::make_unique<AdaptiveStepIntegrator>(method, control, [name = std::string(method.name), type](const CountedSystem& system, const StepControl& c) {
        // the driver's h0 is only its own first step (gsl_odeiv2_driver_apply); evolve_apply steps with the loop's h
        return std::make_unique<GslAdaptiveStepper>(system, name, type, c, 1e-3);
      });
    return std::make_unique<FixedStepIntegrator>(
        method, control, [name = std::string(method.name), type, control](const CountedSystem& system) {
          return std::make_unique<GslFixedStepper>(system, name, type, control);
        });
  };
}

}  // namespace

// GSL's orders as measured by the convergence tests: its embedded pairs advance with the higher-order
// solution (rk2 is a 2(3) pair of order 3, rk8pd an 8(9) pair of order 9)
void register_gsl_methods(MethodTable& table) {
  struct Stepper {
    std::string_view name;
    const gsl_odeiv2_step_type* type;
    std::string_view description;
    Order order;
    DenseMatrices dense;
  };
  const Stepper steppers[] = {
      {"gsl-rk2", gsl_odeiv2_step_rk2, "explicit embedded Runge-Kutta (2,3), advances with the third-order solution", {3, 3, "3"}, DenseMatrices::none},
      {"gsl-rk4", gsl_odeiv2_step_rk4, "explicit classical Runge-Kutta, error by step doubling", {4, 4, "4"}, DenseMatrices::none},
      {"gsl-rkf45", gsl_odeiv2_step_rkf45, "explicit embedded Runge-Kutta-Fehlberg (4,5)", {5, 5, "5"}, DenseMatrices::none},
      {"gsl-rkck", gsl_odeiv2_step_rkck, "explicit embedded Runge-Kutta Cash-Karp (4,5)", {5, 5, "5"}, DenseMatrices::none},
      {"gsl-rk8pd", gsl_odeiv2_step_rk8pd, "explicit embedded Runge-Kutta Prince-Dormand (8,9), advances with the ninth-order solution",
       {9, 9, "9"}, DenseMatrices::none},
      {"gsl-rk1imp", gsl_odeiv2_step_rk1imp, "implicit Gaussian first order Runge-Kutta (backward Euler)", {1, 1, "1"}, DenseMatrices::always},
      {"gsl-rk2imp", gsl_odeiv2_step_rk2imp, "implicit Gaussian second order Runge-Kutta (midpoint)", {2, 2, "2"}, DenseMatrices::always},
      {"gsl-rk4imp", gsl_odeiv2_step_rk4imp, "implicit Gaussian fourth order Runge-Kutta", {4, 4, "4"}, DenseMatrices::always},
      {"gsl-bsimp", gsl_odeiv2_step_bsimp, "implicit Bulirsch-Stoer (Bader-Deuflhard)", {1, 12, "variable"}, DenseMatrices::always},
      {"gsl-msadams", gsl_odeiv2_step_msadams, "variable order Adams, functional iteration", {1, 12, "1-12"}, DenseMatrices::none},
      {"gsl-msbdf", gsl_odeiv2_step_msbdf, "variable order BDF, Newton iteration", {1, 5, "1-5"}, DenseMatrices::always},
  };
  for (const auto& s : steppers)
    table.add({.name = s.name,
               .family = Family::gsl,
               .source = Source::gsl,
               .description = s.description,
               .order = s.order,
               .stepping = Stepping::fixed_or_adaptive,
               .dense = s.dense,
               .make = gsl_integrator(s.type)});
}

}  // namespace stepwise
