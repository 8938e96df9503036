// A sweep's results between ranks (report/pack.hpp) and the points' shares (report/sweep.hpp): what a rank
// hands over is what the other ranks get back, bit for bit, and the shares by cost are balanced as list
// scheduling guarantees. (Under mpirun end to end: mpi_ranks.py.)
#include "models/model.hpp"
#include "report/pack.hpp"
#include "report/sweep.hpp"
#include "run/measure.hpp"
#include "verification/convergence.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

namespace stepwise {
namespace {

template <class T>
T round_trip(const T& value) {
  pack::Writer w;
  pack::put(w, value);
  pack::Reader r(w.bytes());
  T back{};
  pack::get(r, back);
  EXPECT_TRUE(r.done());
  return back;
}

TEST(Sweep, AMeasuredRunComesBackBitForBit) {
  const auto model = make_model("bouncing-ball", {});
  const Measured m = run_and_measure(*model, "rk4", StepControl::fixed(1e-3), 2.0, 0.1);
  ASSERT_FALSE(m.result.events.empty());  // the impacts are carried too
  const Measured back = round_trip(m);
  EXPECT_EQ(back.t_out, m.t_out);
  EXPECT_EQ(back.error, m.error);
  EXPECT_EQ(back.result.status, m.result.status);
  EXPECT_EQ(back.result.message, m.result.message);
  EXPECT_EQ(back.result.t_stop, m.result.t_stop);
  EXPECT_EQ(back.result.y_stop, m.result.y_stop);
  EXPECT_EQ(back.result.trajectory.t, m.result.trajectory.t);
  ASSERT_EQ(back.result.trajectory.y.size(), m.result.trajectory.y.size());
  for (size_t i = 0; i < m.result.trajectory.y.size(); ++i) EXPECT_EQ(back.result.trajectory.y[i], m.result.trajectory.y[i]);
  EXPECT_EQ(back.result.stats.rhs_evals, m.result.stats.rhs_evals);
  EXPECT_EQ(back.result.stats.cpu_seconds, m.result.stats.cpu_seconds);
  ASSERT_EQ(back.result.events.size(), m.result.events.size());
  for (size_t i = 0; i < m.result.events.size(); ++i) {
    EXPECT_EQ(back.result.events[i].t, m.result.events[i].t);
    EXPECT_EQ(back.result.events[i].kind, m.result.events[i].kind);
    EXPECT_EQ(back.result.events[i].event, m.result.events[i].event);
  }
}

TEST(Sweep, NestedAndComplexValuesComeBackAndShortBytesAreRefused) {
  const Eigen::VectorXcd spectrum = Eigen::VectorXcd::Random(7);
  EXPECT_EQ(round_trip(spectrum), spectrum);
  const std::pair<std::optional<double>, std::vector<std::string>> mixed{std::nullopt, {"a", "", "b c"}};
  EXPECT_EQ(round_trip(mixed), mixed);
  const nlohmann::json j{{"frames", {1, 2, 3}}, {"renderer", "llvmpipe"}};
  EXPECT_EQ(round_trip(j), j);
  pack::Writer w;
  pack::put(w, std::string("a longer string"));
  const std::string cut = w.bytes().substr(0, w.bytes().size() - 3);
  pack::Reader r(cut);
  std::string s;
  EXPECT_THROW(pack::get(r, s), std::runtime_error);
}

TEST(Sweep, EveryPointGoesToOneRankAndTheSharesAreBalancedAsListSchedulingBounds) {
  std::mt19937 random(7);
  std::lognormal_distribution<double> cost(0.0, 1.5);  // costs over orders of magnitude, as the studies' are
  for (const int ranks : {1, 2, 3, 5, 16}) {
    std::vector<double> costs(200);
    for (double& c : costs) c = cost(random);
    const auto shares = share_by_cost(costs, ranks);
    ASSERT_EQ(shares.size(), static_cast<size_t>(ranks));
    std::vector<int> seen(costs.size(), 0);
    double busiest = 0;
    for (const auto& share : shares) {
      double load = 0;
      for (size_t k = 0; k < share.size(); ++k) {
        ++seen[share[k]];
        load += costs[share[k]];
        if (k > 0) {
          EXPECT_GE(costs[share[k - 1]], costs[share[k]]);  // the costliest first
        }
      }
      busiest = std::max(busiest, load);
    }
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
    // Graham (1969): the costliest-first greedy share is within 4/3 - 1/(3m) of the best possible, which is at
    // least the mean share and the costliest point
    const double total = std::accumulate(costs.begin(), costs.end(), 0.0);
    const double lower = std::max(total / ranks, *std::max_element(costs.begin(), costs.end()));
    EXPECT_LE(busiest, (4.0 / 3 - 1.0 / (3 * ranks)) * lower * (1 + 1e-12)) << ranks << " ranks";
    EXPECT_EQ(share_by_cost(costs, ranks), shares);  // the same on every rank
  }
}

TEST(Sweep, OneProcessKeepsTheResultsInPointOrderAndRethrowsAPointsError) {
  const StudyContext ctx{false, 2, nullptr};
  const std::vector<std::string> labels{"a", "b", "c", "d"};
  const auto squares = ctx.sweep<double>(labels, [](size_t i) { return static_cast<double>(i * i); }, {1, 4, 2, 3});
  EXPECT_EQ(squares, (std::vector<double>{0, 1, 4, 9}));
  EXPECT_THROW(ctx.sweep<double>(labels, [](size_t i) -> double { if (i == 2) throw std::runtime_error("point c"); return 0; }), std::runtime_error);
}

}  // namespace
}  // namespace stepwise
