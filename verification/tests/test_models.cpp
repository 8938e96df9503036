// Models: analytic Jacobians against their finite-difference twins, exact solutions against the ODE
// they solve, invariants of the exact solutions, bad parameters.
#include "models/model.hpp"
#include "models/pendulum.hpp"
#include "run/measure.hpp"
#include "solvers/fd_jacobian.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace stepwise {
namespace {

struct Case {
  std::string model;
  Params params;
};

std::vector<Case> cases() {
  return {{"pendulum", {{"theta0", 1.0}, {"omega0", 0.3}}},
          {"pendulum", {{"theta0", 170 * std::numbers::pi / 180}}},
          {"pendulum-small-angle", {{"theta0", 0.2}, {"omega0", -0.1}}},
          {"flow-particle", {}},
          {"flow-particle", {{"y0", 7.0}}},
          {"flow-particle-3d", {{"x0", -0.5}}},
          {"projectile", {{"drag", 0.0}}},
          {"projectile", {{"drag", 0.7}}},
          {"projectile", {{"drag", 30.0}}}};
}

std::string label(const Case& c) {
  std::string s = c.model;
  for (const auto& [k, v] : c.params) s += " " + k + "=" + std::to_string(v);
  return s;
}

TEST(Models, AnalyticJacobianMatchesCentralDifferences) {
  for (const auto& c : cases()) {
    const auto model = make_model(c.model, c.params);
    const int n = model->size();
    for (const double t : {0.0, 0.37}) {
      const Eigen::VectorXd y = model->has_exact() ? model->exact(t) : model->initial_state();
      Eigen::MatrixXd analytic(n, n), fd(n, n);
      model->as<DenseJacobian>()->jacobian(t, y, analytic);
      fd_jacobian(*model, t, y, fd);
      EXPECT_LT((analytic - fd).lpNorm<Eigen::Infinity>(), tolerance::jacobian_fd * (1 + analytic.lpNorm<Eigen::Infinity>())) << label(c);
    }
  }
}

TEST(Models, ExactSolutionSatisfiesTheOde) {
  for (const auto& c : cases()) {
    const auto model = make_model(c.model, c.params);
    ASSERT_TRUE(model->has_exact()) << label(c);
    EXPECT_LT((model->exact(0) - model->initial_state()).lpNorm<Eigen::Infinity>(), 1e-14) << label(c);
    Eigen::VectorXd f(model->size());
    for (const double t : {0.1, 0.55, 0.9}) {
      // d/dt of the exact solution by a central difference
      const double h = tolerance::exact_derivative_fd_step;
      const Eigen::VectorXd dydt = (model->exact(t + h) - model->exact(t - h)) / (2 * h);
      model->rhs(t, model->exact(t), f);
      EXPECT_LT((dydt - f).lpNorm<Eigen::Infinity>(), tolerance::exact_ode_residual * (1 + f.lpNorm<Eigen::Infinity>())) << label(c) << " t=" << t << " dydt " << dydt.transpose() << " f " << f.transpose();
    }
  }
}

TEST(Models, ExactPendulumConservesEnergyAndHasTheEllipticPeriod) {
  const double theta0 = 2.5;
  const auto model = make_model("pendulum", {{"theta0", theta0}});
  const double e0 = *model->energy(model->initial_state());
  const double period = pendulum_period(theta0, 9.81, 1.0);
  for (int k = 1; k <= 1000; k += 37) {
    const double t = 0.123 * k;
    EXPECT_NEAR(*model->energy(model->exact(t)), e0, tolerance::exact_invariant * e0);
  }
  // after whole periods the state returns; far along, the reduction modulo 4K keeps the digits
  EXPECT_LT((model->exact(1000 * period) - model->initial_state()).lpNorm<Eigen::Infinity>(), 1e-9);
  // half a period later the bob is at -theta0
  EXPECT_NEAR(model->exact(period / 2)[0], -theta0, 1e-12);
}

TEST(Models, ExactProjectileWithoutDragConservesEnergy) {
  // kinetic plus potential energy along the exact parabola: a term missing from either changes it by O(1)
  const auto model = make_model("projectile", {{"drag", 0.0}, {"vx0", 3.0}, {"vy0", 12.0}});
  const double e0 = *model->energy(model->initial_state());
  for (const double t : {0.3, 1.1, 2.4}) EXPECT_NEAR(*model->energy(model->exact(t)), e0, tolerance::exact_invariant * std::abs(e0)) << t;
}

TEST(Models, AStateFarFromTheOriginIsNotTakenForABlowUp) {
  // the blow-up bound scales with the initial state: a projectile thrown 1e13 m from the origin runs as one at it
  const auto model = make_model("projectile", {{"x0", 1e13}});
  const Measured m = run_and_measure(*model, "rk4", StepControl::fixed(1e-3), 1.0, 1.0);
  EXPECT_EQ(m.result.status, Status::ok) << m.result.message;
}

TEST(Models, BadParametersNameTheirKey) {
  EXPECT_THROW(make_model("pendulum", {{"length", 0.0}}), BadParameter);
  EXPECT_THROW(make_model("pendulum", {{"g", -1.0}}), BadParameter);
  EXPECT_THROW(make_model("pendulum", {{"mass", std::nan("")}}), BadParameter);
  EXPECT_THROW(make_model("projectile", {{"drag", -0.1}}), BadParameter);
  try {
    make_model("pendulum", {{"lenght", 1.0}});
    FAIL() << "unknown key accepted";
  } catch (const BadParameter& e) {
    EXPECT_EQ(e.key, "lenght");
    EXPECT_NE(std::string(e.what()).find("length"), std::string::npos) << "the message lists the known keys";
  }
}

}  // namespace
}  // namespace stepwise
