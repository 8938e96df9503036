// Solver backends: counting, the pitfalls of the exact library versions, divergence, and the seeds'
// claim about explicit and implicit Euler in a position-independent force field.
#include "models/model.hpp"
#include "solvers/capabilities/inline_rhs.hpp"
#include "solvers/tableaus/tsitouras54.hpp"
#include "solvers/tableaus/verner98.hpp"
#include "solvers/tableaus/dense_weight.hpp"
#include "solvers/method_table.hpp"
#include "solvers/step_controller.hpp"
#include "run/measure.hpp"
#include "verification/order_fit.hpp"
#include "verification/tolerances.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace stepwise {
namespace {

// forwards to a model and counts the calls of f it sees itself; optionally hides the analytic Jacobian. It
// hides the model's inline f (solvers/capabilities/inline_rhs.hpp), which a stepper would call, and count,
// without passing through here: AStepperCallingTheModelsFInline... holds that path to this one
class SelfCounting final : public OdeSystem {
 public:
  SelfCounting(const Model& m, bool hide_jacobian) : model_(m), hide_(hide_jacobian) {}
  int size() const override { return model_.size(); }
  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) const override {
    ++calls;
    model_.rhs(t, y, f);
  }
  const void* capability(const std::type_info& type) const override {
    if (type == typeid(InlineRhs) || (hide_ && type == typeid(DenseJacobian))) return nullptr;
    return model_.capability(type);
  }
  mutable long calls = 0;

 private:
  const Model& model_;
  bool hide_;
};

TEST(Solvers, EveryCallOfTheRightHandSideIsCountedWithOrWithoutAnAnalyticJacobian) {
  const auto model = make_model("pendulum", {{"theta0", 2.0}});
  const std::vector<double> t_out{1.0, 2.0};
  for (const auto& method : methods()) {
    if (!method_applies(method, *model)) continue;
    for (const bool hide : {false, true}) {
      SelfCounting system(*model, hide);
      const auto control = method.adaptive() ? StepControl::adaptive(1e-8, 1e-10) : StepControl::fixed(1e-2);
      const RunResult r = make_integrator(method.name, control)->integrate(system, 0, model->initial_state(), t_out);
      ASSERT_EQ(r.status, Status::ok) << method.name << ": " << r.message;
      // difference-quotient Jacobians (CVODE's, GSL's implicit steppers') included: nothing escapes the wrapper
      EXPECT_EQ(r.stats.rhs_evals, system.calls) << method.name << (hide ? " without" : " with") << " analytic Jacobian";
      EXPECT_GT(r.stats.steps, 0) << method.name;
    }
  }
}

// the model with its inline f hidden and all else passed on; counts the calls of f it sees
class WithoutInlineF final : public OdeSystem {
 public:
  explicit WithoutInlineF(const Model& m) : model_(m) {}
  int size() const override { return model_.size(); }
  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) const override {
    ++calls;
    model_.rhs(t, y, f);
  }
  bool autonomous() const override { return model_.autonomous(); }
  const void* capability(const std::type_info& type) const override { return type == typeid(InlineRhs) ? nullptr : model_.capability(type); }
  mutable long calls = 0;

 private:
  const Model& model_;
};

// A stepper that calls the model's f inline (rk4, euler, symplectic-euler and the hand-written pairs, fixed
// and adaptive, on the pendulum, the projectile and the flow field) takes the same steps, to the bit, and
// counts the same calls of f as through the system: the inline f is the model's own formula (kernels/), and
// the step's arithmetic is written once for both paths. Every method runs it (those with no inline path
// trivially agree)
TEST(Solvers, AStepperCallingTheModelsFInlineTakesTheSameStepsAndCountsAsThroughTheSystem) {
  const std::pair<const char*, Params> models[] = {
      {"pendulum", {{"theta0", 2.0}}}, {"pendulum-small-angle", {{"theta0", 2.0}}}, {"projectile", {{"drag", 0.5}}}, {"flow-particle", {}}};
  for (const auto& [name, params] : models) {
    const auto model = make_model(name, params);
    ASSERT_NE(model->as<InlineRhs>(), nullptr) << name;
    const std::vector<double> t_out{0.5, 1.5};
    for (const auto& method : methods()) {
      if (!method_applies(method, *model)) continue;
      std::vector<StepControl> controls;
      if (method.fixed_step()) controls.push_back(StepControl::fixed(1e-2));
      if (method.adaptive()) controls.push_back(StepControl::adaptive(1e-8, 1e-10));
      for (const StepControl& control : controls) {
        const std::string what = fmt::format("{} {} {}", name, method.name, control.dt ? "fixed" : "adaptive");
        const auto integrator = make_integrator(method.name, control);
        const RunResult direct = integrator->integrate(*model, 0, model->initial_state(), t_out);
        WithoutInlineF through(*model);
        const RunResult counted = integrator->integrate(through, 0, model->initial_state(), t_out);
        // (gsl-msadams fails here at dt 1e-2, alike on both paths)
        ASSERT_EQ(direct.status, counted.status) << what << ": " << direct.message;
        for (Eigen::Index i = 0; i < model->size(); ++i) EXPECT_EQ(direct.y_stop[i], counted.y_stop[i]) << what << " entry " << i;
        EXPECT_EQ(direct.stats.rhs_evals, through.calls) << what;
        EXPECT_EQ(direct.stats.steps, counted.stats.steps) << what;
      }
    }
  }
}

// the model with an event that never fires (g = 1): the fixed-step loop then takes every step itself
class WithIdleEvent final : public OdeSystem, public EventSource {
 public:
  explicit WithIdleEvent(const Model& m) : model_(m) { event_.push_back({"never", 0, [](double, const Eigen::VectorXd&) { return 1.0; }, {}}); }
  int size() const override { return model_.size(); }
  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) const override { model_.rhs(t, y, f); }
  bool autonomous() const override { return model_.autonomous(); }
  std::span<const Event> events() const override { return event_; }
  const void* capability(const std::type_info& type) const override {
    return type == typeid(EventSource) ? &as_part<EventSource>(*this) : model_.capability(type);
  }

 private:
  const Model& model_;
  std::vector<Event> event_;
};

// A run without events or projection has the stepper take its full steps itself (FixedStepper::plain_steps,
// rk4, euler, symplectic-euler): the same steps, to the bit, as the loop takes one by one, and a blow-up at the
// same time, step and state (the steppers test for it once a block of PlainStepping::test_every steps, and step
// a block past the bound again from its start); output times off the step grid (0.505 s at dt 0.01) so that
// the loop's landing steps are in it
TEST(Solvers, TheSteppersOwnRunOfStepsIsTheLoopsStepByStep) {
  const auto model = make_model("pendulum", {{"theta0", 2.0}});
  const WithIdleEvent stepwise_loop(*model);
  struct Case {
    const char* method;
    double dt;
    double blowup;  // lowered from 1e12 so that the growing swing crosses |y| = blowup |y0|
    long steps;     // the steps to the blow-up (0: none)
  };
  // a bound of 5 |y0| = 10 lies past the true swing's |omega| <= 5.3, so only a run whose energy grows crosses
  // it, its angle going over the top without end: the first step at dt = 2 s (|y| = 2 |y0|: inside the first
  // block), steps 18-30 in the methods' unstable ranges (inside the second; a report at the block's end, the
  // 32nd step, fails it)
  const Case cases[] = {{"rk4", 1e-2, 1e12, 0}, {"euler", 1e-2, 1e12, 0}, {"symplectic-euler", 1e-2, 1e12, 0},
                        {"rk4", 2.0, 2, 1},     {"euler", 2.0, 2, 1},     {"symplectic-euler", 2.0, 2, 1},
                        {"rk4", 1.2, 5, 18},    {"euler", 0.1, 5, 30},    {"symplectic-euler", 0.6, 5, 30}};
  for (const auto& [method, dt, blowup, steps] : cases) {
    StepControl control = StepControl::fixed(dt);
    control.blowup = blowup;
    const auto integrator = make_integrator(method, control);
    const std::vector<double> t_out = dt > 0.1 ? std::vector{5.5, 200.0} : std::vector{0.505, 1.5, 20.0};
    const RunResult own = integrator->integrate(*model, 0, model->initial_state(), t_out);
    const RunResult looped = integrator->integrate(stepwise_loop, 0, model->initial_state(), t_out);
    EXPECT_EQ(own.status, looped.status) << method << " dt " << dt;
    EXPECT_EQ(own.t_stop, looped.t_stop) << method << " dt " << dt;
    EXPECT_EQ(own.status, steps > 0 ? Status::diverged : Status::ok) << method << " dt " << dt;
    if (steps > 0) {
      EXPECT_EQ(own.stats.steps, steps) << method << " dt " << dt;
    }
    EXPECT_EQ(own.stats.steps, looped.stats.steps) << method << " dt " << dt;
    EXPECT_EQ(own.stats.rhs_evals, looped.stats.rhs_evals) << method << " dt " << dt;
    EXPECT_EQ(own.trajectory.t, looped.trajectory.t) << method << " dt " << dt;
    for (Eigen::Index i = 0; i < model->size(); ++i) EXPECT_EQ(own.y_stop[i], looped.y_stop[i]) << method << " dt " << dt;
  }
}

// the flow field (x, y, sin x) offering its Jacobian as a sparse matrix, so that CVODE BDF takes its KLU path
class SparseFlow final : public OdeSystem, public SparseJacobian {
 public:
  explicit SparseFlow(const Model& m) : model_(m) {}
  int size() const override { return model_.size(); }
  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) const override { model_.rhs(t, y, f); }
  void sparse_jacobian(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::SparseMatrix<double>& J) const override {
    Eigen::MatrixXd dense(size(), size());
    model_.as<DenseJacobian>()->jacobian(t, y, dense);
    J = dense.sparseView();
    ++sparse_calls;
  }
  const void* capability(const std::type_info& type) const override { return offer(type, as_part<SparseJacobian>(*this)); }
  mutable long sparse_calls = 0;

 private:
  const Model& model_;
};

TEST(Solvers, CvodeBdfWithKluMatchesTheDenseSolver) {
  const auto model = make_model("flow-particle-3d");
  SparseFlow sparse(*model);
  const auto control = StepControl::adaptive(1e-10, 1e-12);
  const RunResult klu = make_integrator("cvode-bdf", control)->integrate(sparse, 0, model->initial_state(), std::vector{1.0});
  const RunResult dense = make_integrator("cvode-bdf", control)->integrate(*model, 0, model->initial_state(), std::vector{1.0});
  ASSERT_EQ(klu.status, Status::ok) << klu.message;
  EXPECT_GT(sparse.sparse_calls, 0) << "the sparse Jacobian was used";
  EXPECT_GT(klu.stats.factorizations, 0);
  // both solve the same Newton systems exactly (a 3x3 LU either way): the runs agree to round-off in the
  // solves, far below the tolerance, and both are within the tolerance-proportional bound of the exact solution
  const double bound = tolerance::adaptive_agreement_factor * control.rtol * model->exact(1.0).lpNorm<Eigen::Infinity>();
  EXPECT_LT(max_norm_error(klu.trajectory.y.back(), model->exact(1.0)), bound);
  EXPECT_LT(max_norm_error(klu.trajectory.y.back(), dense.trajectory.y.back()), bound);
}

TEST(Solvers, CvodeAdamsRunsWithItsFixedPointSolver) {
  // with CVODE's default Newton solver and no linear solver, CVode returns -13 (CV_LINIT_FAIL)
  const auto model = make_model("pendulum");
  const Measured m = run_and_measure(*model, "cvode-adams", StepControl::adaptive(1e-10, 1e-12), 10.0, 1.0);
  ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
  EXPECT_EQ(m.result.stats.linear_solves, 0) << "fixed-point iteration solves no linear system";
  EXPECT_LT(*m.error, 1e-6);
}

TEST(Solvers, GslImplicitSteppersRunWithoutAnAnalyticJacobian) {
  // GSL 2.7's rk1imp, rk2imp, rk4imp, bsimp and msbdf dereference the Jacobian: NULL segfaults
  const auto model = make_model("pendulum");
  for (const char* method : {"gsl-rk1imp", "gsl-rk2imp", "gsl-rk4imp", "gsl-bsimp", "gsl-msbdf"}) {
    for (const auto& control : {StepControl::fixed(1e-2), StepControl::adaptive(1e-8, 1e-10)}) {
      SelfCounting without(*model, true), with(*model, false);
      const auto integrator = make_integrator(method, control);
      const RunResult a = integrator->integrate(without, 0, model->initial_state(), std::vector{2.0});
      const RunResult b = integrator->integrate(with, 0, model->initial_state(), std::vector{2.0});
      ASSERT_EQ(a.status, Status::ok) << method << ": " << a.message;
      EXPECT_GT(a.stats.jac_evals, 0) << method << " used a finite-difference Jacobian";
      // the Jacobian only steers the iteration: central differences (relative error ~1e-10) change the result
      // by no more than the iteration's own tolerance
      const double difference = (a.trajectory.y.back() - b.trajectory.y.back()).lpNorm<Eigen::Infinity>();
      EXPECT_LT(difference, tolerance::jacobian_steering) << method;
    }
  }
}

TEST(Solvers, GslRk4CostsElevenCallsPerStepAndIsSixteenTimesMoreAccurate) {
  // GSL rk4 takes one full step (4 calls) and two half steps (4 + 4) sharing k1, and returns the
  // half-step result: 11 calls per step, and the error of classical RK4 at h/2, i.e. 2^4 = 16 times smaller.
  // Fixed-step comparisons must therefore count RHS evaluations, not steps.
  const auto model = make_model("pendulum", {{"theta0", 1.0}});
  const double h = 2.0 / 400;
  const Measured textbook = run_and_measure(*model, "rk4", StepControl::fixed(h), 2.0, 2.0);
  const Measured gsl = run_and_measure(*model, "gsl-rk4", StepControl::fixed(h), 2.0, 2.0);
  EXPECT_EQ(textbook.result.stats.rhs_evals, 4 * textbook.result.stats.steps);
  EXPECT_EQ(gsl.result.stats.rhs_evals, 11 * gsl.result.stats.steps);
  const double ratio = *textbook.error / *gsl.error;
  std::cout << "error ratio textbook rk4 / gsl-rk4 at h = " << h << ": " << ratio << '\n';
  EXPECT_NEAR(ratio, tolerance::gsl_rk4_ratio, tolerance::gsl_rk4_ratio_band * tolerance::gsl_rk4_ratio);
}

TEST(Solvers, FixedStepGslRunsAreNeverRejectedByErrorControl) {
  // gsl_odeiv2_driver_apply_fixed_step would test this step against the tolerance and fail; a fixed step is a fixed step
  const auto model = make_model("pendulum", {{"theta0", 2.0}});
  for (const char* method : {"gsl-rkf45", "gsl-rkck", "gsl-rk8pd", "gsl-rk2"}) {
    StepControl control = StepControl::fixed(0.25);
    control.rtol = 1e-12;
    control.atol = 1e-15;
    const Measured m = run_and_measure(*model, method, control, 10.0, 10.0);
    EXPECT_EQ(m.result.status, Status::ok) << method << ": " << m.result.message;
    EXPECT_EQ(m.result.stats.steps, 40) << method;
    EXPECT_EQ(m.result.stats.rejected, 0) << method;
  }
}

// dy/dt = y^2, y(0) = 1: y = 1 / (1 - t) blows up at t = 1
class BlowUp final : public OdeSystem {
 public:
  int size() const override { return 1; }
  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) const override { f[0] = y[0] * y[0]; }
};

TEST(Solvers, ABlowUpIsReportedAsDivergedAtTheTimeItHappened) {
  BlowUp system;
  const Eigen::VectorXd y0 = Eigen::VectorXd::Constant(1, 1.0);
  const std::vector<double> t_out{0.5, 1.5, 2.0};
  for (const auto& method : methods()) {
    if (!method_applies(method, system)) continue;
    auto control = method.adaptive() ? StepControl::adaptive(1e-8, 1e-10) : StepControl::fixed(1e-4);
    // CVODE Adams' fixed-point iteration needs h |df/dy| = 2 h y < 1, so its steps collapse near the
    // singularity: a step budget ends it (measured: 5e7 steps, a minute, without one)
    control.max_steps = 200'000;
    const RunResult r = make_integrator(method.name, control)->integrate(system, 0, y0, t_out);
    // the state passes 1e12 within 1e-12 of the singularity for an exact solver; fixed-step methods lag it by O(dt).
    // An implicit step may instead find no solution: y1 = y0 + h y1^2 has none once y0 > 1/(4h), and that
    // is reported as the Newton failure it is
    std::cout << method.name << ": " << to_string(r.status) << " at t = " << r.t_stop << " after " << r.stats.steps << " steps\n";
    if (r.status == Status::failed) EXPECT_NE(r.message.find("t = "), std::string::npos) << method.name << ": " << r.message;
    else EXPECT_EQ(r.status, Status::diverged) << method.name << ": " << to_string(r.status) << " " << r.message;
    EXPECT_GT(r.t_stop, 0.99) << method.name;
    EXPECT_LT(r.t_stop, 1.1) << method.name;
    EXPECT_TRUE(r.y_stop.allFinite()) << method.name;
    EXPECT_EQ(r.trajectory.t.size(), 1u) << method.name << " kept only the output before the blow-up";
  }
}

TEST(Solvers, ExplicitEulerBlowsUpOnStiffDragBeyondItsStabilityLimit) {
  // v' = -k v: explicit Euler multiplies v by (1 - k dt) per step, unstable for dt > 2/k
  const auto model = make_model("projectile", {{"drag", 100.0}});
  const Measured m = run_and_measure(*model, "euler", StepControl::fixed(0.05), 10.0, 0.1);
  EXPECT_EQ(m.result.status, Status::diverged);
  EXPECT_LT(m.result.t_stop, 10.0);
  EXPECT_FALSE(m.error.has_value());
  const Measured implicit = run_and_measure(*model, "implicit-euler", StepControl::fixed(0.05), 10.0, 0.1);
  EXPECT_EQ(implicit.result.status, Status::ok);
}

TEST(Solvers, ExplicitAndImplicitEulerShareVelocitiesButNotPositionsUnderConstantForce) {
  // The seeds claim explicit and implicit Euler coincide when the force does not depend on position.
  // Only the velocity update coincides (v1 = v0 - h g either way); positions use v0 (explicit) or v1
  // (implicit), so y_implicit - y_explicit = h (vy_n - vy_0) = -h g t_n exactly, and x agrees.
  const double h = 1e-2, t_end = 2.0, g = 9.81;
  const auto model = make_model("projectile", {{"drag", 0.0}, {"g", g}});
  const Measured ex = run_and_measure(*model, "euler", StepControl::fixed(h), t_end, t_end);
  const Measured im = run_and_measure(*model, "implicit-euler", StepControl::fixed(h), t_end, t_end);
  const Eigen::VectorXd a = ex.result.trajectory.y.back(), b = im.result.trajectory.y.back();
  const double ulp = std::numeric_limits<double>::epsilon();
  const double roundoff = tolerance::roundoff_per_step * ulp * static_cast<double>(ex.result.stats.steps);
  EXPECT_NEAR(a[2], b[2], roundoff * (1 + std::abs(a[2])));
  EXPECT_NEAR(a[3], b[3], roundoff * (1 + std::abs(a[3])));
  EXPECT_NEAR(a[0], b[0], roundoff * (1 + std::abs(a[0])));
  EXPECT_NEAR(b[1] - a[1], -h * g * t_end, roundoff * (1 + std::abs(a[1])));
  // with drag, even the velocities part: (1 - k h)^n against (1 + k h)^-n
  const auto dragged = make_model("projectile", {{"drag", 1.0}});
  const Measured ex2 = run_and_measure(*dragged, "euler", StepControl::fixed(h), t_end, t_end);
  const Measured im2 = run_and_measure(*dragged, "implicit-euler", StepControl::fixed(h), t_end, t_end);
  EXPECT_GT(std::abs(ex2.result.trajectory.y.back()[2] - im2.result.trajectory.y.back()[2]), 1e-3);
}

TEST(Solvers, UnknownMethodsAndMismatchedStepControlsAreRefused) {
  EXPECT_THROW(make_integrator("rk5", StepControl::fixed(0.1)), BadMethod);
  EXPECT_THROW(make_integrator("rk4", StepControl::adaptive(1e-6, 1e-9)), BadMethod);
  EXPECT_THROW(make_integrator("cvode-bdf", StepControl::fixed(0.1)), BadMethod);
  EXPECT_THROW(make_integrator("rk4", StepControl::fixed(-1)), BadMethod);
  EXPECT_THROW(make_integrator("gsl-rkf45", StepControl::adaptive(0, 1e-9)), BadMethod);
  const auto flow = make_model("flow-particle");
  EXPECT_THROW(make_integrator("symplectic-euler", StepControl::fixed(0.1))->integrate(*flow, 0, flow->initial_state(), std::vector{1.0}),
               BadMethod);
}

// a hand-written pair's coefficients against the conditions every order-p tableau meets: each row of a sums to
// its node (c_i = sum_j a_ij), the weights integrate polynomials of degree < p exactly (sum_i b_i c_i^(k-1)
// = 1/k, k = 1..p, the quadrature conditions), and the error weights vanish on constants (sum e_i = 0). A
// digit mistyped in b or c breaks one of them by far more than the double-precision rounding of 16 terms
template <class T>
void expect_consistent_tableau(const char* name) {
  for (int i = 0; i < T::stages; ++i) {
    double row = 0;
    for (int j = 0; j < i; ++j) row += T::a[i][j];
    EXPECT_NEAR(row, T::c[i], tolerance::tableau_roundoff) << name << " row " << i;
  }
  for (int k = 1; k <= T::order; ++k) {
    double quadrature = 0;
    for (int i = 0; i < T::stages; ++i) quadrature += T::b[i] * std::pow(T::c[i], k - 1);
    EXPECT_NEAR(quadrature, 1.0 / k, tolerance::tableau_roundoff) << name << " quadrature condition k = " << k;
  }
  double e = 0;
  for (int i = 0; i < T::stages; ++i) e += T::e[i];
  EXPECT_NEAR(e, 0.0, tolerance::tableau_roundoff) << name;
}

TEST(Solvers, TheHandWrittenPairsTableausMeetTheirOrderConditions) {
  expect_consistent_tableau<tableau::Tsitouras54>("tsitouras54");
  expect_consistent_tableau<tableau::Verner98>("verner98");
}

// one step of size h of a pair's tableau on y' = -y + sin(3t) from (0, 1), a smooth scalar problem with a
// time-dependent f: its stages, the interpolant's own included (y = 1.3 e^-t + (sin 3t - 3 cos 3t) / 10)
template <class T>
std::array<double, T::dense_stages> scalar_stages(double h) {
  std::array<double, T::dense_stages> k{};
  for (int i = 0; i < T::dense_stages; ++i) {
    double y = 1;
    for (int j = 0; j < i; ++j) y += h * T::a[i][j] * k[j];
    k[i] = -y + std::sin(3 * T::c[i] * h);
  }
  return k;
}
double scalar_exact(double t) { return 1.3 * std::exp(-t) + (std::sin(3 * t) - 3 * std::cos(3 * t)) / 10; }

// the pair's error estimate h sum_i e_i k_i over that step, divided by `scale`: err ~ C h^k with k =
// estimate_order + 1
template <class T>
double scaled_error_estimate(double h, double scale) {
  const auto k = scalar_stages<T>(h);
  double estimate = 0;
  for (int i = 0; i < T::stages; ++i) estimate += h * T::e[i] * k[i];
  return std::abs(estimate) / scale;
}

// the retry after a rejected step is the step at which the error model err ~ h^k meets the tolerance, times
// the safety factor: its error is safety^k of the tolerance (0.59 for Tsitouras' k = 5). The tolerance's step
// h* is found by bisection on the real tableau's estimate; the first try at 2 h* is rejected. Tsitouras' pair
// only: Verner's estimate reaches its asymptote h^9 only below steps whose estimate is round-off (at a scale of
// 1e-17 h* = 0.044 and err(2h*)/err(h*) is still 2^9/5.4); both pairs share the one controller
template <class T>
void expect_retry_meets_the_error_model(const char* name, double scale) {
  constexpr double k = T::estimate_order + 1;
  double lo = 1e-6, hi = 0.5;  // err(lo) < 1 < err(hi)
  ASSERT_LT(scaled_error_estimate<T>(lo, scale), 1) << name;
  ASSERT_GT(scaled_error_estimate<T>(hi, scale), 1) << name;
  for (int i = 0; i < 100; ++i) (scaled_error_estimate<T>(0.5 * (lo + hi), scale) < 1 ? lo : hi) = 0.5 * (lo + hi);
  const double h_star = lo, first = 2 * h_star;
  const PiStepController controller(k);
  const double retry = first * controller.rejected(scaled_error_estimate<T>(first, scale));
  const double ratio = scaled_error_estimate<T>(retry, scale) / std::pow(PiStepController::safety, k);
  std::cout << name << ": h* = " << h_star << ", retry " << retry / h_star << " h*, its error over safety^k " << ratio << '\n';
  EXPECT_NEAR(ratio, 1, tolerance::error_model_deviation(k, first)) << name;
}

TEST(Solvers, ARejectedStepIsRetriedWhereTheErrorModelMeetsTheToleranceWithTheSafetyMargin) {
  expect_retry_meets_the_error_model<tableau::Tsitouras54>("tsitouras54", 1e-15);
}

// a pair's interpolant y0 + h sum_i b_i(theta) k_i: b_i(0) = 0 and b_i(1) = b_i (the step's own solution;
// 0 for the interpolant's own stages), and its error over one step from the exact y0 (the largest at theta =
// 1/20 ... 19/20) falls as h^(q+1), q its documented order; `coarsest` and `halvings`: the steps whose errors
// lie between the asymptote and round-off. The error over the step, not at a few thetas: at one theta the
// h^(q+1) term can nearly cancel for this f (Verner's at 3/4 falls by 2^6.9 then 2^8.3 per halving), and
// that local dip says nothing about the order. Lower side only: a slope above q + 1 is no defect
template <class T>
void expect_interpolant_of_order(const char* name, double coarsest, int halvings) {
  for (int i = 0; i < T::dense_stages; ++i) {
    EXPECT_NEAR(tableau::dense_weight<T>(i, 0), 0, tolerance::tableau_roundoff) << name << " stage " << i;
    EXPECT_NEAR(tableau::dense_weight<T>(i, 1), i < T::stages ? T::b[i] : 0, tolerance::tableau_roundoff) << name << " stage " << i;
  }
  std::vector<double> hs, errors;
  for (int n = 0; n <= halvings; ++n) {
    const double h = coarsest / std::pow(2.0, n);
    const auto k = scalar_stages<T>(h);
    double error = 0;
    for (int m = 1; m < 20; ++m) {
      const double theta = m / 20.0;
      double y = 1;
      for (int i = 0; i < T::dense_stages; ++i) y += h * tableau::dense_weight<T>(i, theta) * k[static_cast<size_t>(i)];
      error = std::max(error, std::abs(y - scalar_exact(theta * h)));
    }
    hs.push_back(h);
    errors.push_back(error);
  }
  const double slope = loglog_slope(hs, errors);
  std::cout << name << " interpolant: error over the step " << errors.front() << " -> " << errors.back() << ", slope " << slope << '\n';
  EXPECT_GT(errors.back(), tolerance::roundoff_floor) << name << ": the window reaches round-off";
  EXPECT_GT(slope, T::dense_order + 1 - tolerance::order_band) << name;
}

TEST(Solvers, TheHandWrittenPairsInterpolantsHaveTheirOrder) {
  expect_interpolant_of_order<tableau::Tsitouras54>("tsitouras54", 0.4, 4);
  expect_interpolant_of_order<tableau::Verner98>("verner98", 1.2, 2);
}

// Through the integrator: with dense output the steps pass over output times, so a run's steps do not depend
// on how many outputs it asks for (both runs ask for the same first one, which sets the first trial step), and
// every output, interpolated, is within the tolerance's bound of the exact flow
TEST(Solvers, TheHandWrittenPairsOutputsAreInterpolatedWithinTheTolerance) {
  const auto model = make_model("flow-particle");
  const double rtol = 1e-10, t_end = 1.0;
  std::vector<double> many;
  for (int i = 1; i <= 1000; ++i) many.push_back(t_end * i / 1000);
  const std::vector<double> few{many.front(), t_end};
  for (const char* method : {"tsitouras54", "verner98"}) {
    const auto integrator = make_integrator(method, StepControl::adaptive(rtol, 1e-3 * rtol));
    const RunResult dense = integrator->integrate(*model, 0, model->initial_state(), many);
    const RunResult sparse = integrator->integrate(*model, 0, model->initial_state(), few);
    ASSERT_EQ(dense.status, Status::ok) << method << ": " << dense.message;
    ASSERT_EQ(dense.trajectory.y.size(), many.size()) << method;
    EXPECT_EQ(dense.stats.steps, sparse.stats.steps) << method;
    EXPECT_GT(dense.stats.rhs_evals, sparse.stats.rhs_evals) << method << ": the interpolated steps cost their stages";
    double worst = 0, size = 0;
    for (size_t i = 0; i < many.size(); ++i) {
      worst = std::max(worst, max_norm_error(dense.trajectory.y[i], model->exact(many[i])));
      size = std::max(size, dense.trajectory.y[i].lpNorm<Eigen::Infinity>());
    }
    std::cout << method << ": " << dense.stats.steps << " steps, " << dense.stats.rhs_evals << " calls of f with 1000 outputs ("
              << sparse.stats.rhs_evals << " with 2), worst output error " << worst << '\n';
    EXPECT_LT(worst, tolerance::adaptive_agreement_factor * rtol * size) << method;
  }
}

}  // namespace
}  // namespace stepwise
