// The height field on MPI ranks (solvers/distributed_wave.hpp): strong and weak scaling of the distributed
// step on this machine, the halo's messages and bytes a step, the latency and bandwidth of a message here, and
// the model they give for a cluster. Run it under mpirun:
//
//   mpirun -np 2 bench/bench_mpi_wave        # (as root: --allow-run-as-root)
//
// Every rank runs every benchmark in step (fixed iteration counts, so that no rank decides alone to run one
// more); an iteration's time is the slowest rank's, as the step is done when the last block is. The one-rank
// step is measured in the same run, on rank 0 alone (the others wait), so the speed-up is a ratio of one run.
//
// The model (Hockney's): a step on P ranks of an n x n grid costs
//     T(P, n) = (n^2 / P) t_cell + m (alpha + beta b),   m = 4 messages of b = 8 n / sqrt(P) bytes,
// the compute with the cell cost t_cell measured here on one rank (cache effects aside: a block past the caches
// streams from memory, as measured at 4096^2), and the halo in the slowest direction of the four, alpha and beta
// measured here by a ping-pong between two ranks on this machine (shared memory), and for a cluster taken from
// the interconnect's figures (connectx6_alpha, connectx6_beta: distributed_wave.hpp, with the model, HaloModel).
// The halo begins to dominate where m (alpha + beta b) > (n^2 / P) t_cell.
#include "models/model.hpp"
#include "run/ranks.hpp"
#include "solvers/distributed_wave.hpp"
#include "solvers/method_table.hpp"

#include <mpi.h>

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace {

constexpr int steps = 20;  // steps per iteration
const stepwise::WaveGridView water{0, 0.02, 1.0, 0.2};

stepwise::WaveCoefficients coefficients(int n) {
  stepwise::WaveGridView g = water;
  g.points = n;
  return stepwise::wave_coefficients(g, 0.5 * stepwise::wave_stable_dt(g));
}

// seconds of `work` on the slowest rank
template <class Work>
double slowest(Work&& work) {
  stepwise::ranks::max_over_ranks(0);  // everyone starts together
  const auto start = std::chrono::steady_clock::now();
  work();
  return stepwise::ranks::max_over_ranks(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

std::map<std::string, double> seconds;  // an iteration's, by benchmark name, for the summary

// `steps` distributed steps of an n x n grid on every rank; range(1): overlap the halo with the interior
void BM_step(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  stepwise::DistributedWave grid(n, n, coefficients(n));
  std::vector<double> z(static_cast<size_t>(n) * n, 0.0);
  for (int i = 1; i < n - 1; ++i) z[static_cast<size_t>(i) * n + n / 2] = 1e-3;
  grid.set(z.data(), z.data());
  for (auto _ : state) state.SetIterationTime(slowest([&] { grid.step(steps, state.range(1) != 0); }));
  const auto halo = grid.halo();
  state.counters["cells"] = benchmark::Counter(static_cast<double>(n) * n * steps * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["halo_msgs"] = halo.messages;
  state.counters["halo_bytes"] = static_cast<double>(halo.bytes);
}

// the same on rank 0 alone (the others wait at the end): the one-rank time of the speed-up
void BM_step_one_rank(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::unique_ptr<stepwise::DistributedWave> grid;
  if (stepwise::ranks::rank() == 0) {
    grid = std::make_unique<stepwise::DistributedWave>(n, n, coefficients(n), true);
    std::vector<double> z(static_cast<size_t>(n) * n, 0.0);
    grid->set(z.data(), z.data());
  }
  for (auto _ : state) state.SetIterationTime(slowest([&] { if (grid) grid->step(steps, false); }));
  state.counters["cells"] = benchmark::Counter(static_cast<double>(n) * n * steps * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

// the run's path (what `mpirun -np N stepwise run scenes/pool.toml` does): wave-fd over run_steps steps of the pool
// at n^2 (one drop, at t = 0), the fixed-step loop with its divergence test around the stepper. range(1):
// 0 on every rank's block (wave_fd_distributed); 1 the same stepper on rank 0 alone, its block the whole grid;
// 2 wave-fd as one process runs it (the table's method), on rank 0 alone
constexpr int run_steps = 100;  // enough that the run's start (its state's first touch, a restart) is a few percent
void BM_run(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)), how = static_cast<int>(state.range(1));
  const auto model = stepwise::make_model("pool", {{"size", n}, {"drops", 1}});
  const auto& view = *model->as<stepwise::WaveGridView>();
  const auto control = stepwise::StepControl::fixed(0.5 * stepwise::wave_stable_dt(view));
  const std::vector<double> t_out{run_steps * *control.dt};
  const bool rank0 = stepwise::ranks::rank() == 0;
  std::unique_ptr<stepwise::DistributedWave> grid;
  if (how == 0 || (how == 1 && rank0)) grid = std::make_unique<stepwise::DistributedWave>(n, n, stepwise::WaveCoefficients{}, how == 1);
  long taken = 0;
  for (auto _ : state)
    state.SetIterationTime(slowest([&] {
      if (grid) taken = stepwise::wave_fd_distributed(*grid, view, *model->as<stepwise::WaveBlocksView>(), control, t_out).stats.steps;
      else if (how == 2 && rank0) taken = stepwise::make_integrator("wave-fd", control)->integrate(*model, 0.0, model->initial_state(), t_out).stats.steps;
    }));
  state.counters["steps"] = static_cast<double>(taken);
}

// a message of range(0) bytes from rank 0 to rank 1 and back, ten times an iteration: an iteration's time is
// set to one message's (a twentieth)
void BM_pingpong(benchmark::State& state) {
  const int bytes = static_cast<int>(state.range(0));
  std::vector<char> message(static_cast<size_t>(bytes), 'x');
  const int rank = stepwise::ranks::rank();
  for (auto _ : state) {
    const double t = slowest([&] {
      for (int k = 0; k < 10; ++k) {
        if (rank == 0) {
          MPI_Send(message.data(), bytes, MPI_BYTE, 1, 0, MPI_COMM_WORLD);
          MPI_Recv(message.data(), bytes, MPI_BYTE, 1, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        } else if (rank == 1) {
          MPI_Recv(message.data(), bytes, MPI_BYTE, 0, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
          MPI_Send(message.data(), bytes, MPI_BYTE, 0, 0, MPI_COMM_WORLD);
        }
      }
    });
    state.SetIterationTime(t / 20);
  }
}

void grids(benchmark::internal::Benchmark* b) {
  for (const int n : {1024, 2048, 4096})
    for (const int overlap : {0, 1}) b->Args({n, overlap});
}
BENCHMARK(BM_step)->Apply(grids)->Iterations(5)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_step_one_rank)->Arg(1024)->Arg(2048)->Arg(4096)->Iterations(5)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_run)->Args({2048, 0})->Args({2048, 1})->Args({2048, 2})->Iterations(3)->UseManualTime()->Unit(benchmark::kMillisecond);

// rank 0's report; the other ranks print nothing
class Quiet : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context&) override { return true; }
  void ReportRuns(const std::vector<Run>&) override {}
};

class Collect : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& r : runs) seconds[r.run_name.str()] = r.real_accumulated_time / static_cast<double>(r.iterations);
    ConsoleReporter::ReportRuns(runs);
  }
};

}  // namespace

int main(int argc, char** argv) {
  stepwise::ranks::Session mpi(argc, argv);
  const int P = stepwise::ranks::size();
  // weak scaling: the grid whose blocks are as large as one rank's 2048^2
  const int weak = static_cast<int>(std::lround(2048 * std::sqrt(static_cast<double>(P))));
  if (P > 1) benchmark::RegisterBenchmark("BM_step_weak", BM_step)->Args({weak, 1})->Iterations(5)->UseManualTime()->Unit(benchmark::kMillisecond);
  // the message's cost: alpha from 8 bytes, beta from 4 MB
  if (P == 2)
    for (const long bytes : {8L, 4L << 20})
      benchmark::RegisterBenchmark("BM_pingpong", BM_pingpong)->Arg(bytes)->Iterations(200)->UseManualTime()->Unit(benchmark::kMicrosecond);
  benchmark::Initialize(&argc, argv);
  Collect collect;
  Quiet quiet;
  benchmark::RunSpecifiedBenchmarks(stepwise::ranks::rank() == 0 ? static_cast<benchmark::BenchmarkReporter*>(&collect) : &quiet);
  benchmark::Shutdown();
  if (stepwise::ranks::rank() != 0) return 0;

  const auto per_step = [&](const std::string& name) { return seconds[name] / steps; };
  std::printf("\n%d rank(s)\n", P);
  for (const int n : {1024, 2048, 4096}) {
    const double one = per_step(fmt::format("BM_step_one_rank/{}/iterations:5/manual_time", n));
    for (const int overlap : {0, 1}) {
      const double many = per_step(fmt::format("BM_step/{}/{}/iterations:5/manual_time", n, overlap));
      std::printf("strong scaling %d^2%s: %.3f ms a step on %d rank(s), %.3f on one: speed-up %.2f (efficiency %.2f)\n", n,
                  overlap ? " (halo overlapped)" : "", many * 1e3, P, one * 1e3, one / many, one / many / P);
    }
  }
  {
    const auto per_run_step = [&](int how) { return seconds[fmt::format("BM_run/2048/{}/iterations:3/manual_time", how)] / run_steps; };
    const double blocks = per_run_step(0), alone = per_run_step(1), serial = per_run_step(2);
    std::printf("run's path 2048^2 (pool, wave-fd, fixed-step loop): %.3f ms a step on %d rank(s), %.3f on one rank's block: speed-up %.2f;"
                " wave-fd as one process %.3f (the blocks' stepper on one rank / it: %.2f)\n",
                blocks * 1e3, P, alone * 1e3, alone / blocks, serial * 1e3, alone / serial);
  }
  if (P > 1) {
    const double one = per_step("BM_step_one_rank/2048/iterations:5/manual_time");
    const double many = per_step(fmt::format("BM_step_weak/{}/1/iterations:5/manual_time", weak));
    std::printf("weak scaling: %d^2 on %d ranks (blocks of 2048^2) %.3f ms a step against 2048^2 on one %.3f: efficiency %.2f\n", weak, P,
                many * 1e3, one * 1e3, one / many);
  }
  // the model, from the cell cost of the one-rank step past the caches (4096^2: the blocks of a large grid)
  const double t_cell = per_step("BM_step_one_rank/4096/iterations:5/manual_time") / (4096.0 * 4096.0);
  double alpha = 0, beta = 0;
  if (P == 2) {
    const double small = seconds["BM_pingpong/8/iterations:200/manual_time"];
    const double large = seconds[fmt::format("BM_pingpong/{}/iterations:200/manual_time", 4L << 20)];
    alpha = small;
    beta = (large - small) / (4 << 20);
    std::printf("shared memory here: alpha %.2f us, beta %.3f ns/byte (%.1f GB/s)\n", alpha * 1e6, beta * 1e9, 1e-9 / beta);
  }
  // the model against this run's 2-rank steps: 2 x 1 blocks, one neighbour, one message of a row a step
  if (P == 2)
    for (const int n : {1024, 2048, 4096}) {
      const double t_n = per_step(fmt::format("BM_step_one_rank/{}/iterations:5/manual_time", n)) / (static_cast<double>(n) * n);
      // two blocks of n/2 rows: one neighbour, one message of a row (a quarter of HaloModel's four)
      const stepwise::HaloModel here{t_n, alpha, beta};
      const double model = here.compute_seconds(2, n) + alpha + beta * 8.0 * n;
      const double measured = per_step(fmt::format("BM_step/{}/0/iterations:5/manual_time", n));
      std::printf("model here, %d^2 on 2 ranks: %.3f ms a step (halo %.1f us), measured %.3f: ratio measured / model %.2f\n", n, model * 1e3,
                  (alpha + beta * 8.0 * n) * 1e6, measured * 1e3, measured / model);
    }
  std::printf("cell cost t_cell (one rank, 4096^2): %.3f ns\n", t_cell * 1e9);
  const stepwise::HaloModel cluster{t_cell, stepwise::connectx6_alpha, stepwise::connectx6_beta};
  std::printf("model for a cluster (alpha %.1f us, beta 1/%.0f GB/s, ConnectX-6 HDR), time a step in ms [halo share]:\n", cluster.alpha * 1e6,
              1e-9 / cluster.beta);
  std::printf("%10s", "n \\ P");
  for (const int p : {64, 256, 1024, 4096}) std::printf("%22d", p);
  std::printf("\n");
  for (const int n : {4096, 16384, 65536}) {
    std::printf("%10d", n);
    for (const int p : {64, 256, 1024, 4096})
      std::printf("%14.4f [%4.0f%%]", cluster.step_seconds(p, n) * 1e3, 100 * cluster.halo_seconds(p, n) / cluster.step_seconds(p, n));
    std::printf("\n");
  }
  for (const int n : {4096, 16384, 65536}) {
    const double p = cluster.crossover_ranks(n);
    std::printf("%d^2: the halo reaches the compute at about %.0f ranks (blocks of %.0f^2)\n", n, p, n / std::sqrt(p));
  }
  return 0;
}
