// The seeds' three-level scheme (wave_step.hpp) on a grid split among MPI ranks: a 2D Cartesian decomposition
// (MPI_Dims_create, MPI_Cart_create) of a rows x cols grid, boundary included and held still as in one process,
// each rank holding its block inside one layer of halo. A step exchanges that layer of z^k with the four
// neighbours (non-blocking, a row as it lies, a column as a strided MPI datatype) and updates the block by the
// same row kernels as one process (wave_step_rows), so every cell gets the same bits whoever owns it. With
// `overlap` the block's inner cells, which need no halo, are updated while the messages are in flight and the
// block's edge cells after them. Blocks differ by at most one row or column (any grid, any rank count, down to
// one row and one column a rank). MPI's types stay in distributed_wave.cpp; MPI must have been started
// (run/ranks.hpp), or with one process it need not be.
#pragma once

#include <stepwise/solvers/integrator.hpp>
#include <stepwise/solvers/wave_step.hpp>

#include <array>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

namespace stepwise {

// more ranks along a side than the grid has rows or columns there: the message names both numbers
struct DecompositionError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The time of a distributed step (Hockney's model): P ranks on an n x n grid, blocks of (n/sqrt P)^2 cells,
// each exchanging 4 messages of 8 n/sqrt(P) bytes a step (a block with four neighbours: the slowest):
//     T(P, n) = (n^2 / P) t_cell + 4 (alpha + beta 8 n / sqrt P)
// with t_cell a cell's update on one rank, alpha a message's latency and beta its time per byte. The one
// formula bench_mpi_wave and the report's scaling section both use.
struct HaloModel {
  double t_cell = 0, alpha = 0, beta = 0;  // s, s, s/byte

  double compute_seconds(double ranks, double n) const { return n * n / ranks * t_cell; }
  double halo_seconds(double ranks, double n) const { return 4 * (alpha + beta * 8 * n / std::sqrt(ranks)); }
  double step_seconds(double ranks, double n) const { return compute_seconds(ranks, n) + halo_seconds(ranks, n); }
  // the rank count where the halo's time reaches the compute's (a 1% search from one rank)
  double crossover_ranks(double n) const {
    double p = 1;
    while (p < 1e12 && halo_seconds(p, n) < compute_seconds(p, n)) p *= 1.01;
    return p;
  }
};

// a cluster's interconnect, from its maker's figures: NVIDIA ConnectX-6 (HDR InfiniBand), "200Gb/s ... sub-600ns
// latency" (ConnectX-6 user manual, docs.nvidia.com/networking/display/ConnectX6EN/Introduction): 0.6 us, 25 GB/s.
// An MPI message costs somewhat more than the adapter's latency, so the model is a lower bound on the halo
inline constexpr double connectx6_alpha = 0.6e-6;
inline constexpr double connectx6_beta = 1 / 25e9;

class DistributedWave {
 public:
  using Block = GridBlock;
  // the halo a rank exchanges per step: messages it sends (as many as it receives) and their bytes
  struct Halo {
    int messages = 0;
    long bytes = 0;
  };

  // every rank of the world (`alone`: this rank by itself, the whole grid its block), on a rows x cols grid
  // (each at least 3); DecompositionError if a side has more ranks than points
  DistributedWave(int rows, int cols, const WaveCoefficients& k, bool alone = false);
  ~DistributedWave();
  DistributedWave(const DistributedWave&) = delete;
  DistributedWave& operator=(const DistributedWave&) = delete;

  std::array<int, 2> dims() const;  // ranks along the rows and the columns
  Block block() const;              // this rank's
  Halo halo() const;                // this rank's per step

  // the two levels z^{k-1} and z^k of this rank's block, from whole-grid arrays (row-major, rows x cols)
  void set(const double* z_prev, const double* z);
  // `steps` steps
  void step(int steps, bool overlap);
  // z^k of the whole grid on rank 0 (row-major); empty on the others
  std::vector<double> gather() const;
  // any field of this rank's block (rows x cols, row-major) gathered into the whole grid on rank 0
  std::vector<double> gather(const std::vector<double>& block) const;
  // a state (z, v) of this rank's block gathered into the whole grid's (z, v) on rank 0; empty on the others
  Eigen::VectorXd gather_state(const Eigen::VectorXd& block_state) const;
  // the largest of every rank's value, on every rank
  double max_over_ranks(double mine) const;

  // z^k inside its halo ((rows + 2) x stride(), the block's cell (a, b) at (a + 1) stride() + b + 1), and its
  // halo filled from the neighbours (blocking): where a right-hand side on this grid reads the heights
  // around its block (solvers/distributed_lines)
  double* level();
  int stride() const;
  void exchange();
  // a block's z (rows x cols, row-major) into level() inside its halo, then exchange()
  void load(const double* z);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// the water's f (models/height_field.cpp's, cell by cell by the same kernel) on this rank's block: y and dydt the
// block's (z, v), the grid's boundary still; `stiff` and `damping` pick the IMEX split's parts, z' = v with
// c^2 Lap z, and -mu v (both: all of f). Collective when `stiff`: z's halo is exchanged through `grid`
void block_rhs(DistributedWave& grid, const WaveGridView& view, const double* y, double* dydt, bool stiff = true, bool damping = true);

// wave-fd on this rank's block of a water model's grid (split by `grid`): the fixed-step loop of one process
// (fixed_step.hpp: steps landing on the output times, the events located and handled, the divergence test)
// around a stepper on the block's state (z, v) that computes every cell by wave-fd's per-cell formulas
// (wave_step.hpp: the scheme continuing, velocity Verlet on a restart) with z's halo exchanged once a step
// (twice on a restart). The divergence test takes the whole grid's norms (MPI_Allreduce) and the events
// depend on t alone (WaveBlocksView), so every rank takes the same steps, and every cell gets the same bits as
// in one process. Collective: every rank calls it. control's observe and sink see the block's state at the
// output times, on every rank; the result's y_stop is the block's.
RunResult wave_fd_distributed(DistributedWave& grid, const WaveGridView& view, const WaveBlocksView& blocks, const StepControl& control,
                              std::span<const double> t_out);

}  // namespace stepwise
