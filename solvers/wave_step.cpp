#include "wave_step.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace stepwise {

WaveCoefficients wave_coefficients(const WaveGridView& grid, double dt) {
  const double r = grid.c * grid.c * dt * dt / (grid.spacing * grid.spacing);  // c^2 dt^2 / d^2
  const double denominator = grid.mu * dt + 2;
  return {(4 - 8 * r) / denominator, (grid.mu * dt - 2) / denominator, 2 * r / denominator};
}

namespace {

// c^2 lambda_max, lambda_max = (8/d^2) cos^2(pi/2N) on N intervals
double highest_w2(const WaveGridView& grid) {
  const double cosine = std::cos(std::numbers::pi / (2 * (grid.points - 1)));
  return grid.c * grid.c * 8 / (grid.spacing * grid.spacing) * cosine * cosine;
}

}  // namespace

double wave_stable_dt(const WaveGridView& grid) { return 2 / std::sqrt(highest_w2(grid)); }

double symplectic_euler_wave_dt(const WaveGridView& grid) {
  const double w2 = highest_w2(grid);
  const double limit = (-grid.mu + std::sqrt(grid.mu * grid.mu + 4 * w2)) / w2;
  return grid.mu > 0 ? std::min(limit, 2 / grid.mu) : limit;
}

std::optional<double> wave_method_stable_dt(std::string_view method, const WaveGridView& grid) {
  if (method == "wave-fd") return wave_stable_dt(grid);
  if (method == "symplectic-euler") return symplectic_euler_wave_dt(grid);
  return std::nullopt;
}

namespace {

// cells [first, last) of one row; every pointer at the row's start, rows `n` apart. Built for AVX2 and
// for plain x86-64, the one chosen at load time: the same IEEE operations in either (no fused
// multiply-adds: -ffp-contract=off), so the same bits; AVX2's four-wide loads and adds lift the in-core
// limit that held the SSE2 loop below the memory bound (bench_wave)
__attribute__((target_clones("avx2", "default"))) void wave_row(const WaveCoefficients& k, int n, int first, int last, const double* __restrict z_prev,
                     const double* __restrict z, double* __restrict z_next) {
  for (int j = first; j < last; ++j) z_next[j] = wave_cell(k, z[j], z_prev[j], neighbour_sum(z, j, n));
}

}  // namespace

void wave_step(const WaveCoefficients& k, int n, const double* z_prev, const double* z, double* z_next, int threads) {
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
  for (int i = 1; i < n - 1; ++i) {
    const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(i) * n;
    wave_row(k, n, 1, n - 1, z_prev + row, z + row, z_next + row);
  }
}

void wave_steps_blocked(const WaveCoefficients& k, int n, int steps, const double* z_prev, const double* z,
                        double* z_prev_out, double* z_out, int threads) {
  // interior cells per tile side: with a halo of 8 the three (128 + 16)^2 buffers take 0.5 MB, half an L2
  constexpr int tile = 128;
  const int per_side = (n - 2 + tile - 1) / tile;
  const int tiles = per_side * per_side;
#pragma omp parallel num_threads(threads)
  {
    std::vector<double> buffers[3];
#pragma omp for schedule(static)
    for (int t = 0; t < tiles; ++t) {
      // the tile's interior rows [r0, r1) and columns [c0, c1), and the halo region [R0, R1) x [C0, C1)
      const int r0 = 1 + (t / per_side) * tile, r1 = std::min(r0 + tile, n - 1);
      const int c0 = 1 + (t % per_side) * tile, c1 = std::min(c0 + tile, n - 1);
      const int R0 = std::max(0, r0 - steps), R1 = std::min(n, r1 + steps);
      const int C0 = std::max(0, c0 - steps), C1 = std::min(n, c1 + steps);
      const int w = C1 - C0;
      const size_t cells = static_cast<size_t>(R1 - R0) * w;
      for (auto& b : buffers) b.resize(cells);
      // level k-1, level k, and the next; the grid's own boundary (held fixed) enters all three
      double* a = buffers[0].data();
      double* b = buffers[1].data();
      double* c = buffers[2].data();
      for (int i = R0; i < R1; ++i) {
        const size_t from = static_cast<size_t>(i) * n + C0, to = static_cast<size_t>(i - R0) * w;
        std::copy_n(z_prev + from, w, a + to);
        std::copy_n(z + from, w, b + to);
        std::copy_n(z + from, w, c + to);
      }
      for (int s = 1; s <= steps; ++s) {
        // the region still valid after s steps: a cell narrower on every side cut from the grid, none
        // on the grid's own boundary, which never moves
        const int i0 = R0 == 0 ? 1 : R0 + s, i1 = R1 == n ? n - 1 : R1 - s;
        const int j0 = C0 == 0 ? 1 : C0 + s, j1 = C1 == n ? n - 1 : C1 - s;
        for (int i = i0; i < i1; ++i) {
          const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(i - R0) * w;
          wave_row(k, w, j0 - C0, j1 - C0, a + row, b + row, c + row);
        }
        std::swap(a, b);  // (a, b, c) <- (b, c, a)
        std::swap(b, c);
      }
      for (int i = r0; i < r1; ++i) {
        const size_t to = static_cast<size_t>(i) * n + c0, from = static_cast<size_t>(i - R0) * w + (c0 - C0);
        std::copy_n(a + from, c1 - c0, z_prev_out + to);
        std::copy_n(b + from, c1 - c0, z_out + to);
      }
    }
  }
}

}  // namespace stepwise
