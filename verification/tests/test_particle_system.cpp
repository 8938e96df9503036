// The particle system: its cell list finds exactly the pairs all-pairs testing finds, its pair forces obey
// Newton's third law, its exact solution solves its ODE in every damping regime, energy is conserved
// without drag and never drifts under symplectic Euler, and bad counts are refused by key.
#include "models/cell_list.hpp"
#include "models/model.hpp"
#include "solvers/capabilities/second_order.hpp"
#include "solvers/method_table.hpp"
#include "run/measure.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <limits>
#include <random>
#include <set>

namespace stepwise {
namespace {

using Pairs = std::set<std::pair<int, int>>;

Pairs cell_list_pairs(const std::vector<double>& p, double cutoff) {
  CellList cells;
  cells.build(p.data(), static_cast<int>(p.size() / 3), cutoff);
  Pairs pairs;
  cells.for_each_pair([&](int i, int j, const Eigen::Vector3d& d, double r2) {
    EXPECT_NE(i, j);
    EXPECT_NEAR(d.squaredNorm(), r2, 0.0);
    EXPECT_TRUE(pairs.emplace(std::min(i, j), std::max(i, j)).second) << "pair " << i << " " << j << " visited twice";
  });
  return pairs;
}

Pairs brute_force_pairs(const std::vector<double>& p, double cutoff) {
  Pairs pairs;
  for_each_pair_brute_force(p.data(), static_cast<int>(p.size() / 3), cutoff,
                            [&](int i, int j, const Eigen::Vector3d&, double) { pairs.emplace(i, j); });
  return pairs;
}

TEST(CellList, FindsExactlyThePairsAllPairsTestingFinds) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  auto cloud = [&](int n, double scale) {
    std::vector<double> p(3 * static_cast<size_t>(n));
    for (auto& x : p) x = scale * u(rng);
    return p;
  };
  std::vector<std::pair<std::string, std::vector<double>>> cases;
  cases.emplace_back("uniform", cloud(3000, 1.0));
  cases.emplace_back("dense, many pairs per cell", cloud(2000, 0.2));
  auto flat = cloud(2000, 1.0);
  for (size_t i = 2; i < flat.size(); i += 3) flat[i] = 0.25;  // all in one plane: one cell thick
  cases.emplace_back("flat", flat);
  auto outlier = cloud(2000, 1.0);
  outlier[0] = 1e9;  // cells of r_c would number 1e10: the grid coarsens instead
  cases.emplace_back("far outlier", outlier);
  auto coincident = cloud(500, 1.0);
  for (size_t i = 0; i < 30; ++i) std::copy_n(coincident.begin(), 3, coincident.begin() + 3 * static_cast<long>(i));
  cases.emplace_back("coincident points", coincident);
  cases.emplace_back("one point", std::vector<double>{0.5, 0.5, 0.5});
  for (const auto& [name, p] : cases) {
    for (const double cutoff : {0.02, 0.1, 0.3}) {
      const Pairs expected = brute_force_pairs(p, cutoff);
      EXPECT_EQ(cell_list_pairs(p, cutoff), expected) << name << ", cutoff " << cutoff;
    }
  }
  std::vector<double> bad = cloud(10, 1.0);
  bad[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(cell_list_pairs(bad, 0.5).empty()) << "a non-finite state has no neighbours";
}

Params system(double count, double repulsion, double drag = 0.1) {
  return {{"count", count}, {"repulsion", repulsion}, {"drag", drag}, {"spread", 0.3}, {"radius", 0.05}};
}

TEST(ParticleSystem, PairForcesAreThoseOfAllPairsAndCancelInTheTotal) {
  const auto with = make_model("particle-system", system(2000, 400));
  const auto without = make_model("particle-system", system(2000, 0));
  const Eigen::VectorXd y = with->initial_state();
  const int n = with->size() / 2;
  Eigen::VectorXd a(n), a0(n);
  with->as<SecondOrderView>()->acceleration(0, y, a);
  without->as<SecondOrderView>()->acceleration(0, y, a0);
  // the same forces summed over all pairs
  Eigen::VectorXd expected = a0;
  long pairs = 0;
  for_each_pair_brute_force(y.data(), n / 3, 0.05, [&](int i, int j, const Eigen::Vector3d& d, double r2) {
    const double r = std::sqrt(r2);
    const Eigen::Vector3d f = 400 * (0.05 - r) / r * d;
    expected.segment<3>(3 * i) += f;
    expected.segment<3>(3 * j) -= f;
    ++pairs;
  });
  ASSERT_GT(pairs, 1000) << "the cloud is dense enough for many contacts";
  const double scale = (a - a0).lpNorm<Eigen::Infinity>();
  EXPECT_LE((a - expected).lpNorm<Eigen::Infinity>(), tolerance::reordered_pair_sum * scale);
  // Newton's third law: the pairs add nothing to the total force
  const Eigen::Map<const Eigen::Matrix3Xd> pa(a.data(), 3, n / 3), pa0(a0.data(), 3, n / 3);
  EXPECT_LE((pa.rowwise().sum() - pa0.rowwise().sum()).lpNorm<Eigen::Infinity>(), tolerance::reordered_pair_sum * scale * pairs);
  // rhs and acceleration agree
  Eigen::VectorXd f(with->size());
  with->rhs(0, y, f);
  EXPECT_EQ(f.tail(n), a);
  EXPECT_EQ(f.head(n), y.tail(n));
}

TEST(ParticleSystem, ExactSolutionSolvesTheOdeUnderOverAndCriticallyDamped) {
  // k = 4: gamma < 4 oscillates, gamma = 4 is critical, gamma > 4 creeps
  for (const double gamma : {0.0, 0.5, 4.0, 9.0}) {
    const auto model = make_model("particle-system", system(20, 0, gamma));
    ASSERT_TRUE(model->has_exact());
    EXPECT_LE((model->exact(0) - model->initial_state()).lpNorm<Eigen::Infinity>(), tolerance::kernel_roundoff);
    const double h = tolerance::exact_derivative_fd_step;
    for (const double t : {0.3, 1.7, 6.0}) {
      const Eigen::VectorXd derivative = (model->exact(t + h) - model->exact(t - h)) / (2 * h);
      Eigen::VectorXd f(model->size());
      model->rhs(t, model->exact(t), f);
      EXPECT_LE((derivative - f).lpNorm<Eigen::Infinity>(), tolerance::exact_ode_residual * (1 + f.lpNorm<Eigen::Infinity>()))
          << "gamma " << gamma << ", t " << t;
    }
  }
  EXPECT_FALSE(make_model("particle-system", system(20, 400))->has_exact());
}

TEST(ParticleSystem, EnergyIsConservedWithoutDragAndSymplecticEulerDoesNotDrift) {
  const auto model = make_model("particle-system", system(300, 400, 0.0));
  const double e0 = *model->energy(model->initial_state());
  const Measured cvode = run_and_measure(*model, "cvode-adams", StepControl::adaptive(1e-9, 1e-12), 1.0, 1.0);
  ASSERT_EQ(cvode.result.status, Status::ok) << cvode.result.message;
  EXPECT_LE(std::abs(*model->energy(cvode.result.y_stop) - e0), tolerance::particle_energy_adaptive * std::abs(e0));

  // the trajectory keeps the model's summary, energy first, not the 1800-entry state
  const Measured se = run_and_measure(*model, "symplectic-euler", StepControl::fixed(2e-3), 40.0, 0.02);
  ASSERT_EQ(se.result.status, Status::ok) << se.result.message;
  ASSERT_EQ(se.result.trajectory.y.front().size(), static_cast<Eigen::Index>(model->summary_names().size()));
  double first = 0, second = 0;
  const size_t half = se.result.trajectory.y.size() / 2;
  for (size_t k = 0; k < se.result.trajectory.y.size(); ++k) {
    const double error = std::abs(se.result.trajectory.y[k][0] - e0);
    (k < half ? first : second) = std::max(k < half ? first : second, error);
  }
  std::cout << "symplectic Euler, h = 2e-3: energy error " << first / std::abs(e0) << " over the first 20 s, "
            << second / std::abs(e0) << " over the next 20 s\n";
  EXPECT_GT(first, 0);
  EXPECT_LE(second, tolerance::symplectic_band_growth * first);
}

TEST(ParticleSystem, DragOnlyTakesEnergyAway) {
  const auto model = make_model("particle-system", system(300, 400, 0.5));
  const Measured m = run_and_measure(*model, "rk4", StepControl::fixed(1e-3), 3.0, 0.01);
  ASSERT_EQ(m.result.status, Status::ok);
  // dE/dt = -gamma sum |v|^2 <= 0: each sample at most the one before, up to rk4's error per interval
  const auto& samples = m.result.trajectory.y;
  double rise = -std::numeric_limits<double>::infinity();
  for (size_t k = 1; k < samples.size(); ++k) rise = std::max(rise, (samples[k][0] - samples[k - 1][0]) / std::abs(samples[0][0]));
  std::cout << "drag: largest energy change between samples " << rise << " of E0\n";
  EXPECT_LE(rise, tolerance::rk4_energy_per_sample);
}

TEST(ParticleSystem, SameSeedSameStateAndBadCountsAreRefusedByKey) {
  const auto a = make_model("particle-system", {{"count", 100}, {"seed", 4}});
  const auto b = make_model("particle-system", {{"count", 100}, {"seed", 4}});
  const auto c = make_model("particle-system", {{"count", 100}, {"seed", 5}});
  EXPECT_EQ(a->initial_state(), b->initial_state());
  EXPECT_NE(a->initial_state(), c->initial_state());
  for (const auto& [key, value] : std::vector<std::pair<std::string, double>>{
           {"count", 0}, {"count", -3}, {"count", 2.5}, {"count", 1e12}, {"seed", -1}, {"seed", 0.5}, {"radius", 0}, {"drag", -1}}) {
    try {
      make_model("particle-system", {{key, value}});
      ADD_FAILURE() << key << " = " << value << " accepted";
    } catch (const BadParameter& e) {
      EXPECT_EQ(e.key, key) << e.what();
    }
  }
}

// the same system with its local acceleration hidden: steppers take the whole-state path
class WholeStateOnly final : public OdeSystem {
 public:
  explicit WholeStateOnly(const OdeSystem& inner) : inner_(inner), view_(*inner.as<SecondOrderView>()) {
    view_.local_acceleration = nullptr;
  }
  int size() const override { return inner_.size(); }
  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) const override { inner_.rhs(t, y, f); }
  const void* capability(const std::type_info& type) const override { return offer(type, view_); }

 private:
  const OdeSystem& inner_;
  SecondOrderView view_;  // the inner system's, less its local acceleration
};

TEST(ParticleSystem, SymplecticEulerInCacheBlocksIsBitForBitTheWholeStateStep) {
  // 5000 particles: 15 000 positions, several blocks and a partial one
  const auto model = make_model("particle-system", {{"count", 5000}, {"repulsion", 0}});
  ASSERT_TRUE(model->as<SecondOrderView>()->local_acceleration);
  const WholeStateOnly whole(*model);
  const auto integrator = make_integrator("symplectic-euler", StepControl::fixed(1e-2));
  const RunResult blocked = integrator->integrate(*model, 0, model->initial_state(), std::vector{1.0});
  const RunResult plain = integrator->integrate(whole, 0, model->initial_state(), std::vector{1.0});
  EXPECT_EQ(blocked.y_stop, plain.y_stop);
  EXPECT_EQ(blocked.stats.rhs_evals, plain.stats.rhs_evals);
  // beyond the stability limit w h < 2 (w = 2 rad/s) both diverge, at the same step
  const auto unstable = make_integrator("symplectic-euler", StepControl::fixed(1.5));
  const RunResult a = unstable->integrate(*model, 0, model->initial_state(), std::vector{300.0});
  const RunResult b = unstable->integrate(whole, 0, model->initial_state(), std::vector{300.0});
  ASSERT_EQ(a.status, Status::diverged);
  EXPECT_EQ(b.status, Status::diverged);
  EXPECT_EQ(a.t_stop, b.t_stop);
  EXPECT_TRUE(a.y_stop.allFinite()) << "the last finite state is kept";
}

TEST(ParticleSystem, MethodsWithDenseMatricesAreRefusedForLargeStatesButNotSparseLuOnes) {
  const auto model = make_model("particle-system", {{"count", 100000}, {"repulsion", 0}});
  EXPECT_GT(dense_matrix_bytes(*find_method("gsl-bsimp"), *model), physical_memory_bytes());
  EXPECT_EQ(dense_matrix_bytes(*find_method("cvode-bdf"), *model), 0) << "the sparse Jacobian goes to KLU or UMFPACK";
  EXPECT_EQ(dense_matrix_bytes(*find_method("implicit-euler"), *model), 0) << "the sparse Jacobian goes to UMFPACK";
  EXPECT_EQ(dense_matrix_bytes(*find_method("rodas5"), *model), 0) << "the sparse Jacobian goes to UMFPACK";
  EXPECT_EQ(dense_matrix_bytes(*find_method("rk4"), *model), 0);
  const auto repelling = make_model("particle-system", {{"count", 100000}, {"repulsion", 1}});
  EXPECT_GT(dense_matrix_bytes(*find_method("cvode-bdf"), *repelling), physical_memory_bytes()) << "no fixed pattern with pairs";
  EXPECT_GT(dense_matrix_bytes(*find_method("implicit-euler"), *repelling), physical_memory_bytes()) << "no fixed pattern with pairs";
}

}  // namespace
}  // namespace stepwise
