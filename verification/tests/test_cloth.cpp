// Mass-spring systems (the cloth issue's first pieces): Voigt springs' internal forces keep momentum, their
// analytic sparse Jacobian against central differences (springs stretched and compressed), and the
// hanging chain settling into its exact static equilibrium under implicit Euler and CVODE BDF with KLU.
#include "models/hanging_chain.hpp"
#include "models/model.hpp"
#include "models/springs.hpp"
#include "solvers/integrator.hpp"
#include "verification/measure.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace stepwise {
namespace {

TEST(Springs, InternalForcesKeepLinearAndAngularMomentum) {
  // 30 nodes joined by 100 random springs, no anchors, some stretched, some compressed, all moving
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  const int nodes = 30;
  Eigen::VectorXd x(3 * nodes), v(3 * nodes), f = Eigen::VectorXd::Zero(3 * nodes);
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    x[i] = u(rng);
    v[i] = u(rng);
  }
  std::vector<Spring> springs;
  for (int s = 0; s < 100; ++s) {
    const int a = static_cast<int>(rng() % nodes), b = (a + 1 + static_cast<int>(rng() % (nodes - 1))) % nodes;
    springs.push_back(Spring{a, b, 1 + u(rng) * 0.9, 100 * (1.5 + u(rng)), 1.5 + u(rng)});
  }
  add_spring_forces(springs, x.data(), v.data(), f.data());
  Eigen::Vector3d total = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero();
  for (int i = 0; i < nodes; ++i) {
    total += f.segment<3>(3 * i);
    moment += x.segment<3>(3 * i).cross(f.segment<3>(3 * i));
  }
  const double scale = f.lpNorm<Eigen::Infinity>() * static_cast<double>(springs.size());
  EXPECT_LT(total.norm(), tolerance::spring_momentum_roundoff * scale);
  EXPECT_LT(moment.norm(), tolerance::spring_momentum_roundoff * scale);
}

TEST(Springs, TheChainsSparseJacobianMatchesCentralDifferences) {
  const auto model = make_model("hanging-chain", {{"nodes", 6}, {"drag", 0.3}, {"damping", 1.5}});
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const double spread : {0.01, 0.08}) {  // springs near rest length, and some compressed to 20%
    Eigen::VectorXd y = model->initial_state();
    for (Eigen::Index i = 0; i < y.size(); ++i) y[i] += (i < y.size() / 2 ? spread : 1.0) * u(rng);
    Eigen::SparseMatrix<double> sparse;
    model->sparse_jacobian(0, y, sparse);
    const Eigen::MatrixXd analytic = Eigen::MatrixXd(sparse);
    // springs 0.1 m long put third derivatives of f at ~c/(m L^2) = 1e5 against |J| ~ 1e3: plain central
    // differences truncate at ~1e-6 of |J| there, so the columns are Richardson-extrapolated from steps h
    // and h/2 (truncation O(h^4)), leaving round-off eps |f| / h
    const auto column = [&](Eigen::Index j, double h) {
      Eigen::VectorXd yp = y, ym = y, fp(y.size()), fm(y.size());
      yp[j] += h;
      ym[j] -= h;
      model->rhs(0, yp, fp);
      model->rhs(0, ym, fm);
      return Eigen::VectorXd((fp - fm) / (2 * h));
    };
    Eigen::MatrixXd fd(y.size(), y.size());
    for (Eigen::Index j = 0; j < y.size(); ++j) fd.col(j) = (4 * column(j, tolerance::richardson_step / 2) - column(j, tolerance::richardson_step)) / 3;
    EXPECT_LT((analytic - fd).lpNorm<Eigen::Infinity>(), tolerance::jacobian_richardson * (1 + analytic.lpNorm<Eigen::Infinity>())) << spread;
  }
}

TEST(HangingChain, SettlesIntoItsExactStaticEquilibrium) {
  const int nodes = 10;
  const double mass = 0.1, stiffness = 100, rest = 0.1, damping = 2, g = 9.81, t_end = 100;
  const auto model = make_model("hanging-chain", {{"nodes", nodes}, {"mass", mass}, {"stiffness", stiffness}, {"rest_length", rest}, {"damping", damping}});
  const std::vector<double> equilibrium = chain_equilibrium(nodes, mass, stiffness, rest, g);
  // it starts at rest length: the bottom node is m g N (N + 1) / (2 c) above its equilibrium
  const double offset = mass * g * nodes * (nodes + 1) / (2 * stiffness);
  EXPECT_NEAR(model->initial_state()[3 * (nodes - 1) + 1] - equilibrium.back(), offset, tolerance::accumulated_roundoff);
  const double rtol = 1e-8;
  for (const auto& [method, control, own_error] :
       {std::tuple{"implicit-euler", StepControl::fixed(1e-2), 0.0}, std::tuple{"cvode-bdf", StepControl::adaptive(rtol, rtol * 1e-2), 10 * rtol * 2.0}}) {
    const Measured m = run_and_measure(*model, method, control, t_end, t_end);
    ASSERT_EQ(m.result.status, Status::ok) << method << m.result.message;
    double worst = 0;
    for (int k = 0; k < nodes; ++k) worst = std::max(worst, std::abs(m.result.y_stop[3 * k + 1] - equilibrium[static_cast<size_t>(k)]));
    const double left = tolerance::chain_settled(t_end, offset, nodes, mass, stiffness, damping) + own_error + tolerance::accumulated_roundoff;
    EXPECT_LT(worst, left) << method;
    // and at rest: no mode moves faster than the highest frequency, 2 sqrt(c/m), times what is left of it
    EXPECT_LT(m.result.y_stop.tail(3 * nodes).lpNorm<Eigen::Infinity>(), 2 * std::sqrt(stiffness / mass) * left) << method;
    std::cout << method << ": largest height error " << worst << " m after " << t_end << " s (" << m.result.stats.steps << " steps)\n";
  }
}

}  // namespace
}  // namespace stepwise
