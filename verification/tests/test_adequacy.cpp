// Model adequacy: the largest amplitude at which the small-angle pendulum stays within a phase error.
#include "models/model.hpp"
#include "models/pendulum.hpp"
#include "verification/adequacy.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace stepwise {
namespace {

TEST(Adequacy, SmallAngleLimitFollowsTheLeadingTermOfThePeriodSeries) {
  // T/T0 = 1 + theta0^2/16 + O(theta0^4): phase error 2 pi N theta0^2 / 16, so theta_max ~ sqrt(8 tol / (pi N));
  // the next term (11/3072 theta0^4) makes the true limit smaller by a relative (11/192) theta0^2 / 2 or so
  for (const double tol : {1e-4, 1e-3, 1e-2}) {
    for (const double n : {1.0, 10.0}) {
      const double estimate = std::sqrt(8 * tol / (std::numbers::pi * n));
      const double limit = small_angle_max_amplitude(tol, n);
      EXPECT_LT(limit, estimate) << tol << " " << n;
      EXPECT_NEAR(limit / estimate, 1.0, 0.06 * estimate * estimate) << tol << " " << n;
    }
  }
}

TEST(Adequacy, PhaseErrorAtTheLimitIsSeenInTheExactSolutions) {
  // after N true periods the nonlinear pendulum is back at theta0, while the small-angle one has turned
  // through 2 pi N T/T0 = 2 pi N + delta: its phase angle atan2(-omega/w, theta) is the phase error delta
  const double tol = 0.1, n = 10;
  const double theta0 = small_angle_max_amplitude(tol, n);
  const auto full = make_model("pendulum", {{"theta0", theta0}});
  const auto linear = make_model("pendulum-small-angle", {{"theta0", theta0}});
  const double w = std::sqrt(9.81);
  const double t = n * pendulum_period(theta0, 9.81, 1.0);
  EXPECT_LT((full->exact(t) - full->initial_state()).lpNorm<Eigen::Infinity>(), 1e-10);
  const Eigen::VectorXd y = linear->exact(t);
  EXPECT_NEAR(std::atan2(-y[1] / w, y[0]), tol, 1e-9);
  std::cout << "small-angle model within " << tol << " rad after " << n << " periods up to theta0 = "
            << theta0 * 180 / std::numbers::pi << " deg\n";
}

}  // namespace
}  // namespace stepwise
