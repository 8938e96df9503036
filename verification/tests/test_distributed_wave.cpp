// The seeds' three-level scheme on a grid split among MPI ranks (solvers/distributed_wave.hpp) gives the same
// bits as one process: a cell's arithmetic does not depend on who owns it. Run under mpirun on 1-4 ranks
// (CTest's mpi_distributed_wave_N); rank 0 gathers and checks, every rank's result decides the exit status.
#include "models/height_field.hpp"
#include "models/model.hpp"
#include "run/ranks.hpp"
#include "solvers/capabilities/wave_grid.hpp"
#include "run/measure.hpp"
#include "solvers/distributed_lines.hpp"
#include "solvers/distributed_wave.hpp"
#include "solvers/method_table.hpp"
#include "verification/tolerances.hpp"
#include "verification/wave_modes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <numbers>

namespace stepwise {
namespace {

// one process, as wave-fd steps (solvers/methods/wave_fd.cpp): the formula cell by cell into a new level
std::vector<double> one_process(const WaveCoefficients& k, int rows, int cols, std::vector<double> z_prev, std::vector<double> z, int steps) {
  std::vector<double> next = z;
  for (int s = 0; s < steps; ++s) {
    for (int i = 1; i < rows - 1; ++i)
      for (int j = 1; j < cols - 1; ++j) {
        const std::ptrdiff_t c = static_cast<std::ptrdiff_t>(i) * cols + j;
        next[c] = wave_cell(k, z[c], z_prev[c], (z[c - cols] + z[c + cols]) + (z[c - 1] + z[c + 1]));
      }
    z_prev.swap(z);
    z.swap(next);
  }
  return z;
}

// a drop-like dent off the centre and a wave moving away from it, zero on the boundary
std::pair<std::vector<double>, std::vector<double>> levels(int rows, int cols) {
  std::vector<double> z_prev(static_cast<size_t>(rows) * cols, 0.0), z = z_prev;
  for (int i = 1; i < rows - 1; ++i)
    for (int j = 1; j < cols - 1; ++j) {
      const double x = (j - 0.37 * cols) / cols, y = (i - 0.58 * rows) / rows, r2 = x * x + y * y;
      z[static_cast<size_t>(i) * cols + j] = -0.01 * std::exp(-r2 / 0.004) + 1e-3 * std::sin(std::numbers::pi * i / (rows - 1)) * std::sin(2 * std::numbers::pi * j / (cols - 1));
      z_prev[static_cast<size_t>(i) * cols + j] = 0.98 * z[static_cast<size_t>(i) * cols + j];
    }
  return {z_prev, z};
}

void expect_same_bits(int rows, int cols, const WaveCoefficients& k, int steps) {
  const auto [z_prev, z] = levels(rows, cols);
  const std::vector<double> reference = one_process(k, rows, cols, z_prev, z, steps);
  for (const bool overlap : {false, true}) {
    DistributedWave grid(rows, cols, k);
    grid.set(z_prev.data(), z.data());
    grid.step(steps, overlap);
    const std::vector<double> gathered = grid.gather();
    if (ranks::rank() != 0) continue;
    ASSERT_EQ(gathered.size(), reference.size());
    size_t differ = 0;
    for (size_t c = 0; c < reference.size(); ++c) differ += gathered[c] != reference[c];  // bits: no tolerance
    EXPECT_EQ(differ, 0u) << rows << " x " << cols << " on " << grid.dims()[0] << " x " << grid.dims()[1] << " ranks, overlap " << overlap;
    std::cout << rows << " x " << cols << ", " << steps << " steps on " << grid.dims()[0] << " x " << grid.dims()[1] << " ranks (overlap " << overlap
              << "): " << differ << " cells differ from one process\n";
  }
}

TEST(DistributedWave, AGridNoRankCountDividesGivesOneProcesssBits) {
  // 97 x 61 (prime and 61): no decomposition divides it; the seeds' coefficients at half the stable step
  const WaveGridView grid{97, 0.02, 1.0, 0.2};
  expect_same_bits(97, 61, wave_coefficients(grid, 0.5 * wave_stable_dt(grid)), 200);
}

TEST(DistributedWave, ThePoolsGridGivesOneProcesssBits) {
  const auto pool = make_model("pool", {{"size", 128}});  // scenes/pool.toml's grid
  const WaveGridView& grid = *pool->as<WaveGridView>();
  expect_same_bits(grid.points, grid.points, wave_coefficients(grid, 5e-3), 400);  // pool.toml's dt, 2 s
}

TEST(DistributedWave, TheHaloIsOneLayerAcrossEachInnerEdgeOfTheDecomposition) {
  const int rows = 97, cols = 61;
  const DistributedWave grid(rows, cols, WaveCoefficients{});
  const auto halo = grid.halo();
  const auto block = grid.block();
  EXPECT_LE(halo.messages, 4);
  // over all ranks: each inner edge between block rows carries its columns both ways, likewise across
  const std::string all = [&] {
    std::string mine(reinterpret_cast<const char*>(&halo.bytes), sizeof halo.bytes);
    return mine;
  }();
  long total = 0;
  for (const auto& bytes : ranks::all_gather(all)) {
    long b = 0;
    std::memcpy(&b, bytes.data(), sizeof b);
    total += b;
  }
  const auto [d0, d1] = grid.dims();
  EXPECT_EQ(total, 8L * 2 * (static_cast<long>(cols) * (d0 - 1) + static_cast<long>(rows) * (d1 - 1)));
  // blocks differ by at most one row or column
  EXPECT_LE(std::abs(block.rows - rows / d0), 1);
  EXPECT_LE(std::abs(block.cols - cols / d1), 1);
}

// the water's check of the scheme against its exact discrete mode (test_wave's), on the state the ranks
// hold, gathered at the end: z^k = a_k sin sin with a_k the three-level recurrence's closed form
TEST(DistributedWave, TheGatheredStateIsTheSchemesExactDiscreteMode) {
  const int n = 33, m = 3, mode_n = 2;
  const WaveGridView grid{n, 0.03, 1.0, 0.5};
  const double dt = 0.9 * wave_stable_dt(grid);
  const long steps = 1000;
  const double lambda = laplacian_eigenvalue(n - 1, grid.spacing, m, mode_n);
  const double a0 = 0.01, a1 = a0 * (1 - 0.5 * dt * dt * grid.c * grid.c * lambda);  // z^1 by Taylor from rest
  const Eigen::VectorXd shape = wave_mode(n, m, mode_n);
  const Eigen::VectorXd z0 = a0 * shape, z1 = a1 * shape;
  DistributedWave distributed(n, n, wave_coefficients(grid, dt));
  distributed.set(z0.data(), z1.data());
  distributed.step(static_cast<int>(steps - 1), false);  // z^1 -> z^steps
  const std::vector<double> z = distributed.gather();
  if (ranks::rank() != 0) return;
  const Eigen::VectorXd expected = scheme_mode_amplitude(scheme_mode(grid, dt, lambda), a0, a1, steps) * shape;
  const double error = (Eigen::Map<const Eigen::VectorXd>(z.data(), n * n) - expected).lpNorm<Eigen::Infinity>() / expected.lpNorm<Eigen::Infinity>();
  std::cout << "mode (3, 2) after " << steps << " steps on " << ranks::size() << " rank(s): relative error against the exact discrete mode " << error << '\n';
  EXPECT_LT(error, tolerance::wave_modal);
}

// wave-fd run on the ranks' blocks (what `mpirun -np N stepwise run scenes/pool.toml` does) against wave-fd in
// one process on a pool whose grid no rank count divides: drops falling inside steps (each located by re-stepping
// from the step's start, then a velocity-Verlet restart), steps shortened onto output times, and every output's
// whole state the same bits, for both ways of placing the events
TEST(DistributedWave, ThePoolRunOnBlocksGivesOneProcesssBitsAtEveryOutputTime) {
  const auto model = make_model("pool", {{"size", 61}, {"drops", 6}, {"interval", 0.25}, {"seed", 3}});
  const std::vector<double> t_out = output_times(1.6, 0.07);  // 0.07 is not a multiple of dt: shortened steps
  for (const EventLocation location : {EventLocation::linear, EventLocation::restep}) {
    StepControl control = StepControl::fixed(4e-3);
    control.event_location = location;
    const int n = model->as<WaveGridView>()->points;
    DistributedWave grid(n, n, WaveCoefficients{});
    StepControl gathered = control;
    gathered.observe = [&grid](const Eigen::VectorXd& block) { return grid.gather_state(block); };
    const RunResult blocks = wave_fd_distributed(grid, *model->as<WaveGridView>(), *model->as<WaveBlocksView>(), gathered, t_out);
    // (no fatal assertion before the loop's next collective call: a rank leaving early would leave the others waiting)
    EXPECT_EQ(blocks.status, Status::ok) << blocks.message;
    if (ranks::rank() != 0) continue;
    const RunResult one = make_integrator("wave-fd", control)->integrate(*model, 0.0, model->initial_state(), t_out);
    EXPECT_EQ(one.status, Status::ok) << one.message;
    EXPECT_EQ(blocks.stats.steps, one.stats.steps);
    // the first drop falls at t = 0, into the initial state; the other five inside steps
    EXPECT_EQ(one.events.size(), 5u);
    if (blocks.events.size() != one.events.size() || blocks.trajectory.y.size() != one.trajectory.y.size()) {
      ADD_FAILURE() << blocks.events.size() << " drops and " << blocks.trajectory.y.size() << " outputs on blocks, " << one.events.size() << " and "
                    << one.trajectory.y.size() << " in one process";
      continue;
    }
    for (size_t e = 0; e < one.events.size(); ++e) EXPECT_EQ(blocks.events[e].t, one.events[e].t) << "drop " << e;
    for (size_t k = 0; k < one.trajectory.y.size(); ++k) {
      if (blocks.trajectory.y[k].size() != one.trajectory.y[k].size()) {
        ADD_FAILURE() << "output " << k << ": " << blocks.trajectory.y[k].size() << " values on blocks, " << one.trajectory.y[k].size() << " in one process";
        continue;
      }
      EXPECT_EQ(std::memcmp(blocks.trajectory.y[k].data(), one.trajectory.y[k].data(), sizeof(double) * static_cast<size_t>(one.trajectory.y[k].size())), 0)
          << "output " << k << " at t = " << one.trajectory.t[k] << ": " << (blocks.trajectory.y[k] - one.trajectory.y[k]).lpNorm<Eigen::Infinity>();
    }
  }
}

// a blow-up is found on every rank at the same step (the norms are the whole grid's), as in one process
TEST(DistributedWave, ARunOnBlocksDivergesWhereOneProcessDoes) {
  const auto model = make_model("pool", {{"size", 45}, {"drops", 2}});
  const WaveGridView& view = *model->as<WaveGridView>();
  const StepControl control = StepControl::fixed(1.05 * wave_stable_dt(view));  // past the scheme's limit
  const std::vector<double> t_out = output_times(60, 1);
  DistributedWave grid(view.points, view.points, WaveCoefficients{});
  const RunResult blocks = wave_fd_distributed(grid, view, *model->as<WaveBlocksView>(), control, t_out);
  EXPECT_EQ(blocks.status, Status::diverged);
  const double t_stop = ranks::max_over_ranks(blocks.t_stop);
  EXPECT_EQ(t_stop, blocks.t_stop) << "every rank stops at the same step";
  if (ranks::rank() != 0) return;
  const RunResult one = make_integrator("wave-fd", control)->integrate(*model, 0.0, model->initial_state(), t_out);
  EXPECT_EQ(one.status, Status::diverged);
  EXPECT_EQ(blocks.t_stop, one.t_stop);
}

// CVODE and ARKODE on the parallel vector against the same methods in one process: the same f cell for cell,
// but the weighted norms summed rank by rank and then across ranks, so the step sizes differ in their last bits
// and the runs agree as two adaptive runs at one tolerance do: within adaptive_agreement_factor rtol |y|. The
// implicit ones (BDF, DIRK, IMEX) solve Newton's systems by GMRES there and by KLU here: each to its own
// tolerance inside Newton's, so again the tolerance's order
TEST(DistributedWave, SundialsOnTheParallelVectorAgreesWithOneProcessToTheTolerancesOrder) {
  const auto model = make_model("standing-wave", {{"size", 41}});
  const WaveGridView& grid = *model->as<WaveGridView>();
  const double rtol = 1e-8, atol = 1e-11, t = 0.5;
  for (const std::string method : {"cvode-adams", "arkode-erk-dormand-prince54", "cvode-bdf", "arkode-dirk-kvaerno43", "arkode-imex-ark436"}) {
    const DistributedLinesRun distributed = lines_distributed(*find_method(method), grid, model->initial_state(), t, rtol, atol);
    ASSERT_TRUE(distributed.failure.empty()) << distributed.failure;
    if (ranks::rank() != 0) continue;
    const Measured serial = run_and_measure(*model, method, StepControl::adaptive(rtol, atol), t, t);
    ASSERT_EQ(serial.result.status, Status::ok) << serial.result.message;
    const Eigen::Map<const Eigen::VectorXd> y(distributed.y.data(), static_cast<Eigen::Index>(distributed.y.size()));
    ASSERT_EQ(y.size(), serial.result.y_stop.size());
    const double size = serial.result.y_stop.lpNorm<Eigen::Infinity>(), gap = (y - serial.result.y_stop).lpNorm<Eigen::Infinity>();
    std::cout << method << ", standing wave 41^2 to " << t << " s, rtol " << rtol << ": " << ranks::size() << " rank(s) " << distributed.steps
              << " steps, one process " << serial.result.stats.steps << "; they differ by " << gap << " (max |y| " << size << ")\n";
    EXPECT_LE(gap, tolerance::adaptive_agreement_factor * rtol * size) << method;
  }
  EXPECT_FALSE(lines_distributed(*find_method("rk4"), grid, model->initial_state(), t, rtol, atol).failure.empty());  // not run this way: said
}

}  // namespace
}  // namespace stepwise

int main(int argc, char** argv) {
  stepwise::ranks::Session mpi(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  if (stepwise::ranks::rank() != 0) delete ::testing::UnitTest::GetInstance()->listeners().Release(::testing::UnitTest::GetInstance()->listeners().default_result_printer());
  const int result = RUN_ALL_TESTS();
  return stepwise::ranks::all_agree(result == 0) ? 0 : 1;
}
