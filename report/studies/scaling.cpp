// The report's study: scaling: what the height field's step would cost on a cluster's ranks (Hockney's model,
// solvers/distributed_wave.hpp), from a cell's cost measured in this run and an interconnect's figures.
#include "report/studies.hpp"

#include "solvers/distributed_wave.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace stepwise {
namespace {

// a cell's update on one core, past the caches: the seeds' step (wave_step, the kernel every rank runs on its
// block) on an n x n grid, the least of three runs of `steps` steps
double cell_seconds(int n, int steps) {
  WaveGridView grid{n, 0.02, 1.0, 0.2};
  const WaveCoefficients k = wave_coefficients(grid, 0.5 * wave_stable_dt(grid));
  std::vector<double> z_prev(static_cast<size_t>(n) * n, 0.0), z = z_prev;
  for (int i = 1; i < n - 1; ++i) z[static_cast<size_t>(i) * n + n / 2] = 1e-3;
  double best = INFINITY;
  for (int run = 0; run < 3; ++run) {
    const auto start = std::chrono::steady_clock::now();
    for (int s = 0; s < steps; ++s) {
      wave_step(k, n, z_prev.data(), z.data());
      z_prev.swap(z);
    }
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best / steps / (static_cast<double>(n) * n);
}

StudyOutput scaling(const StudyContext& ctx) {
  const int n_measured = ctx.quick ? 2048 : 4096, steps = 20;
  const HaloModel cluster{cell_seconds(n_measured, steps), connectx6_alpha, connectx6_beta};
  Table cell{{"grid", "steps", "t_cell_ns"}, {{static_cast<double>(n_measured), static_cast<double>(steps), cluster.t_cell * 1e9}}};
  Table model{{"n", "ranks", "block_side", "compute_ms", "halo_ms", "step_ms", "halo_share"}, {}};
  Table crossover{{"n", "ranks", "block_side"}, {}};
  const std::vector<double> grids{4096, 16384, 65536}, rank_counts{64, 256, 1024, 4096};
  for (const double n : grids) {
    for (const double p : rank_counts)
      model.rows.push_back({n, p, n / std::sqrt(p), cluster.compute_seconds(p, n) * 1e3, cluster.halo_seconds(p, n) * 1e3,
                            cluster.step_seconds(p, n) * 1e3, cluster.halo_seconds(p, n) / cluster.step_seconds(p, n)});
    const double p = cluster.crossover_ranks(n);
    crossover.rows.push_back({n, std::round(p), n / std::sqrt(p)});
  }
  std::string md = fmt::format(
      "What a step of the seeds' water scheme would cost on a cluster's MPI ranks (the grid split into square blocks, "
      "one layer of halo exchanged a step: `solvers/distributed_wave`, which gives one process's bits on any rank count). "
      "Hockney's model T(P, n) = (n²/P) t_cell + 4 (α + β · 8n/√P): a cell's update measured in this run on one core, "
      "t_cell = {:.3f} ns ({}² grid, past the caches, the least of three runs of {} steps), and NVIDIA's figures for "
      "ConnectX-6 HDR InfiniBand, α = {:.1f} µs and 1/β = {:.0f} GB/s (a lower bound on an MPI message's cost). "
      "Measured scaling on this machine's two cores, the shared-memory α and β and the model's check against them: "
      "`mpirun -np 2 bench/bench_mpi_wave` (built by `cmake --build --preset release --target benchmarks`; docs/performance.md).\n\n",
      cluster.t_cell * 1e9, n_measured, steps, cluster.alpha * 1e6, 1e-9 / cluster.beta);
  md += markdown_table(model, {{"n", "grid side", shown_as("{:.0f}")},
                               {"ranks", "ranks", shown_as("{:.0f}")},
                               {"block_side", "block side", shown_as("{:.0f}")},
                               {"step_ms", "ms a step", shown_as("{:.4f}")},
                               {"halo_share", "halo's share", shown_as("{:.3f}")}});
  md += "\nWhere the halo's time reaches the compute's: the block side at which 4 messages a step cost as much as the block's "
        "cells, nearly the same whatever the grid, since there the latency dominates the message:\n\n";
  md += markdown_table(crossover, {{"n", "grid side", shown_as("{:.0f}")},
                                   {"ranks", "ranks", shown_as("{:.0f}")},
                                   {"block_side", "block side", shown_as("{:.0f}")}});
  md += "\nThe model is optimistic near that point: blocks that fit in the caches update faster per cell than t_cell, "
        "which moves the crossover to larger blocks; past it, overlapping the halo with the block's interior starts to pay.\n\n";
  return {{{"scaling_cell", cell}, {"scaling_model", model}, {"scaling_crossover", crossover}}, md, {}};
}

}  // namespace

Study scaling_study() { return {"scaling", "Scaling: the water's step on a cluster's ranks, modelled", scaling}; }

}  // namespace stepwise
