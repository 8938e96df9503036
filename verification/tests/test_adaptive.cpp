// Adaptive methods against the exact pendulum: error falls as rtol tightens, the high-order codes reach
// 1e-6 at 170 degrees, and independent implementations agree within their error bounds.
#include "models/model.hpp"
#include "run/measure.hpp"
#include "verification/order_fit.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace stepwise {
namespace {

const double deg170 = 170 * std::numbers::pi / 180;

TEST(Adaptive, ErrorFallsAsToleranceTightens) {
  const auto model = make_model("pendulum", {{"theta0", 1.0}});
  for (const auto& method : methods()) {
    if (!method.adaptive() || !method_applies(method, *model)) continue;
    // low-order steppers need ~rtol^(-1/p) steps: keep them to tolerances they reach in reasonable work
    const int tightest = method.order.max <= 1 ? 7 : method.order.max == 2 ? 10 : 12;
    std::vector<double> rtols, errors;
    for (int e = 3; e <= tightest; ++e) {
      const double rtol = std::pow(10.0, -e);
      const Measured m = run_and_measure(*model, method.name, StepControl::adaptive(rtol, 1e-3 * rtol), 10.0, 10.0);
      ASSERT_EQ(m.result.status, Status::ok) << method.name << " rtol " << rtol << ": " << m.result.message;
      rtols.push_back(rtol);
      errors.push_back(std::max(*m.error, 1e-16));
    }
    const double slope = loglog_slope(rtols, errors);
    std::cout << method.name << ": error " << errors.front() << " at rtol 1e-3 -> " << errors.back() << " at rtol 1e-"
              << tightest << ", slope " << slope << '\n';
    EXPECT_GT(slope, tolerance::min_tolerance_slope(method.order.min)) << method.name;
    EXPECT_LT(errors.back(), errors.front()) << method.name;
  }
}

TEST(Adaptive, HighOrderMethodsReachTheExactPendulumNearTheSeparatrix) {
  const auto model = make_model("pendulum", {{"theta0", deg170}});
  for (const char* method : {"cvode-adams", "cvode-bdf", "gsl-rk8pd", "gsl-rkck", "gsl-rkf45", "gsl-msadams", "gsl-msbdf", "gsl-bsimp"}) {
    const Measured m = run_and_measure(*model, method, StepControl::adaptive(1e-12, 1e-15), 10.0, 10.0);
    ASSERT_EQ(m.result.status, Status::ok) << method << ": " << m.result.message;
    std::cout << method << " at 170 deg, rtol 1e-12: error " << *m.error << '\n';
    EXPECT_LT(*m.error, tolerance::tight_adaptive_error) << method;
  }
}

TEST(Adaptive, GlobalErrorNearTheSeparatrixIsManyTimesTheTolerance) {
  // a finding for the report, not a bug: the global error exceeds rtol by a factor that grows towards 180 degrees
  const auto near = make_model("pendulum", {{"theta0", deg170}});
  const auto nearer = make_model("pendulum", {{"theta0", 179 * std::numbers::pi / 180}});
  const Measured a = run_and_measure(*near, "cvode-bdf", StepControl::adaptive(1e-10, 1e-13), 10.0, 10.0);
  const Measured b = run_and_measure(*nearer, "cvode-bdf", StepControl::adaptive(1e-10, 1e-13), 10.0, 10.0);
  std::cout << "cvode-bdf rtol 1e-10: error " << *a.error << " at 170 deg, " << *b.error << " at 179 deg\n";
  EXPECT_GT(*a.error, 100 * 1e-10);
  EXPECT_GT(*b.error, *a.error);
}

TEST(Adaptive, CvodeAndGslAgreeWithinTheirTolerances) {
  const auto model = make_model("flow-particle");
  for (const double rtol : {1e-6, 1e-9}) {
    const Measured cvode = run_and_measure(*model, "cvode-adams", StepControl::adaptive(rtol, 1e-3 * rtol), 1.0, 1.0);
    const Measured gsl = run_and_measure(*model, "gsl-rkck", StepControl::adaptive(rtol, 1e-3 * rtol), 1.0, 1.0);
    const Eigen::VectorXd& a = cvode.result.trajectory.y.back();
    const Eigen::VectorXd& b = gsl.result.trajectory.y.back();
    const double bound = tolerance::adaptive_agreement_factor * rtol * a.lpNorm<Eigen::Infinity>();
    EXPECT_LT(max_norm_error(a, b), bound) << "rtol " << rtol;
    EXPECT_LT(*cvode.error, bound);
    EXPECT_LT(*gsl.error, bound);
  }
}

TEST(Adaptive, HandWrittenAndGslRk4AgreeWithinTheirRichardsonErrorEstimates) {
  // no exact solution used: each method's error at h is estimated from its own runs at h and h/2 as
  // (y_h - y_{h/2}) * 2^4 / (2^4 - 1); the two results must differ by no more than the sum of the estimates
  const auto model = make_model("pendulum", {{"theta0", 2.0}});
  auto final_state = [&](const char* method, double h) {
    StepControl c;
    c.dt = h;
    return run_and_measure(*model, method, c, 5.0, 5.0).result.trajectory.y.back();
  };
  const double h = 5.0 / 200;
  const Eigen::VectorXd a = final_state("rk4", h), a2 = final_state("rk4", h / 2);
  const Eigen::VectorXd b = final_state("gsl-rk4", h), b2 = final_state("gsl-rk4", h / 2);
  const double estimate_a = max_norm_error(a, a2) * 16 / 15, estimate_b = max_norm_error(b, b2) * 16 / 15;
  std::cout << "rk4 estimate " << estimate_a << ", gsl-rk4 estimate " << estimate_b << ", difference "
            << max_norm_error(a, b) << ", true errors " << max_norm_error(a, model->exact(5.0)) << " "
            << max_norm_error(b, model->exact(5.0)) << '\n';
  EXPECT_LT(max_norm_error(a, b), estimate_a + estimate_b);
  // and the estimates are estimates of the true errors in this asymptotic range
  EXPECT_NEAR(estimate_a, max_norm_error(a, model->exact(5.0)), tolerance::richardson_band * estimate_a);
  EXPECT_NEAR(estimate_b, max_norm_error(b, model->exact(5.0)), tolerance::richardson_band * estimate_b);
}

}  // namespace
}  // namespace stepwise
