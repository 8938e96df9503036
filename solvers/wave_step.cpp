#include "wave_step.hpp"

#include "solvers/run_support.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <thread>
#include <vector>

#include <immintrin.h>
#include <omp.h>
#include <unistd.h>

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

namespace {

// how far ahead of the sweep the streaming row kernel asks for the two streams it reads from memory
// (z^{k-1} in its own row, z^k a row below): 1024 cells, 8 KB. The hardware prefetcher alone left the loop
// at 0.5-0.7 of the triad on grids past L2, computing and waiting in turn; 4-16 KB ahead measured alike
constexpr std::ptrdiff_t prefetch_cells = 1024;

// a prefetch hint `cells` past p: an address only, never dereferenced (nor formed as a pointer past the
// array), so one past a grid's end is harmless
inline void prefetch(const double* p, std::ptrdiff_t cells, bool write) {
  const auto address = reinterpret_cast<std::uintptr_t>(p) + static_cast<std::uintptr_t>(cells) * sizeof(double);
  if (write) __builtin_prefetch(reinterpret_cast<const void*>(address), 1);
  else __builtin_prefetch(reinterpret_cast<const void*>(address), 0);
}

// cells [first, last) of one row in place (z_prev becomes z^{k+1}); both pointers at the row's start, rows
// `n` apart. Streaming: in chunks of eight cache lines per stream, each chunk asking for the lines
// prefetch_cells ahead. Compiled into each instruction set's kernel below: the same IEEE operations in
// every one (no fused multiply-adds: -ffp-contract=off), so the same bits
template <bool streaming>
[[gnu::always_inline]] inline void row_body(const WaveCoefficients& k, int n, int first, int last, double* __restrict z_prev,
                                            const double* __restrict z) {
  constexpr int chunk = 64, line = 8;
  for (int j0 = first; j0 < last; j0 += chunk) {
    if constexpr (streaming)
      for (int q = 0; q < chunk; q += line) {
        prefetch(z_prev + j0 + q, prefetch_cells, true);
        prefetch(z + j0 + q + n, prefetch_cells, false);
      }
    const int j1 = std::min(j0 + chunk, last);
    for (int j = j0; j < j1; ++j) z_prev[j] = wave_cell(k, z[j], z_prev[j], neighbour_sum(z, j, n));
  }
}

using RowKernel = void (*)(const WaveCoefficients&, int, int, int, double* __restrict, const double* __restrict);

// the kernels, each for one instruction set, all of the same IEEE operations in the same order. Inside the
// caches the limit is in the core, not the memory: six loads (two of them z[j +- 1], split across cache
// lines) and eight flops a cell against the triad's two loads and two flops. The AVX-512 kernel loads z's
// row once, 64-byte aligned, and shifts its neighbours out of the registers (vpermt2pd), so a cell costs one
// aligned load instead of three unaligned ones; streaming from memory the bound is the memory and the AVX2 loop
// with prefetching is the faster there (docs/performance.md's height-field table), so it keeps that role
[[gnu::target("avx512f")]] void row_avx512(const WaveCoefficients& k, int n, int first, int last, double* __restrict z_prev, const double* __restrict z) {
  int j = first;
  const auto cell = [&](int c) { z_prev[c] = wave_cell(k, z[c], z_prev[c], neighbour_sum(z, c, n)); };
  for (; j < last && reinterpret_cast<std::uintptr_t>(z + j) % 64 != 0; ++j) cell(j);
  if (j + 8 <= last) {
    const __m512d self = _mm512_set1_pd(k.self), previous = _mm512_set1_pd(k.previous), neighbours = _mm512_set1_pd(k.neighbours);
    // of two registers (a, b) taken as 16 cells, cells 7-14 (the row shifted right) and 1-8 (shifted left)
    const __m512i shift_right = _mm512_set_epi64(14, 13, 12, 11, 10, 9, 8, 7), shift_left = _mm512_set_epi64(8, 7, 6, 5, 4, 3, 2, 1);
    // z[j-8 .. j-1] and z[j .. j+7]; the loads reach 8 cells either side of [first, last), inside the rows
    // above and below, which every caller's interior row has
    __m512d before = _mm512_loadu_pd(z + j - 8), here = _mm512_load_pd(z + j);
    for (; j + 8 <= last; j += 8) {
      const __m512d after = _mm512_load_pd(z + j + 8);
      const __m512d left = _mm512_permutex2var_pd(before, shift_right, here), right = _mm512_permutex2var_pd(here, shift_left, after);
      // neighbour_sum's order, then wave_cell's
      const __m512d sum = _mm512_add_pd(_mm512_add_pd(_mm512_loadu_pd(z + j - n), _mm512_loadu_pd(z + j + n)), _mm512_add_pd(left, right));
      const __m512d next = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(self, here), _mm512_mul_pd(previous, _mm512_loadu_pd(z_prev + j))),
                                         _mm512_mul_pd(neighbours, sum));
      _mm512_storeu_pd(z_prev + j, next);
      before = here;
      here = after;
    }
  }
  for (; j < last; ++j) cell(j);
}
[[gnu::target("avx2")]] void row_avx2(const WaveCoefficients& k, int n, int first, int last, double* __restrict z_prev, const double* __restrict z) {
  row_body<false>(k, n, first, last, z_prev, z);
}
[[gnu::target("avx2")]] void row_avx2_streaming(const WaveCoefficients& k, int n, int first, int last, double* __restrict z_prev,
                                                 const double* __restrict z) {
  row_body<true>(k, n, first, last, z_prev, z);
}
void row_plain(const WaveCoefficients& k, int n, int first, int last, double* __restrict z_prev, const double* __restrict z) {
  row_body<false>(k, n, first, last, z_prev, z);
}
void row_plain_streaming(const WaveCoefficients& k, int n, int first, int last, double* __restrict z_prev, const double* __restrict z) {
  row_body<true>(k, n, first, last, z_prev, z);
}

// this machine's kernels for grids held in cache and grids streamed from memory
struct RowKernels {
  RowKernel cached, streaming;
};
const RowKernels& row_kernels() {
  static const RowKernels kernels = [] {
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f")) return RowKernels{row_avx512, row_avx2_streaming};
    if (__builtin_cpu_supports("avx2")) return RowKernels{row_avx2, row_avx2_streaming};
    return RowKernels{row_plain, row_plain_streaming};
  }();
  return kernels;
}

// the streaming kernel where a step's two grids pass the core's L2 (1 MB where the C library cannot say)
RowKernel row_kernel_for(int n) {
  static const double l2 = [] {
    const long bytes = sysconf(_SC_LEVEL2_CACHE_SIZE);
    return static_cast<double>(bytes > 0 ? bytes : 1 << 20);
  }();
  const double grids = 2.0 * sizeof(double) * n * static_cast<double>(n);
  return grids > l2 ? row_kernels().streaming : row_kernels().cached;
}

}  // namespace

void wave_step_rows(const WaveCoefficients& k, int stride, int rows, int first, int last, double* z_prev, const double* z) {
  // the kernel for a grid as large as the block's two levels
  const RowKernel row_kernel = row_kernel_for(static_cast<int>(std::sqrt(static_cast<double>(stride) * rows)));
  for (int a = 0; a < rows; ++a) {
    const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(a) * stride;
    row_kernel(k, stride, first, last, z_prev + row, z + row);
  }
}

void wave_step(const WaveCoefficients& k, int n, double* z_prev, const double* z, int threads) {
  const RowKernel row_kernel = row_kernel_for(n);
  std::atomic<double>* const workers = worker_cpu_seconds();  // the run's, its cpu_seconds counting every thread
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    const WorkerCpuTime timed(workers, omp_get_thread_num() != 0);
#pragma omp for schedule(static)
    for (int i = 1; i < n - 1; ++i) {
      const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(i) * n;
      row_kernel(k, n, 1, n - 1, z_prev + row, z + row);
    }
  }
}

void wave_steps_blocked(const WaveCoefficients& k, int n, int steps, double* z_prev, double* z, int threads) {
  // level s (z^{k+s}, s = 1..steps) is written over level s - 2: into z_prev when s is odd, into z when even
  const RowKernel row_kernel = row_kernels().cached;
  const int asked = std::clamp(threads, 1, std::max(steps, 1));
  // each worker's progress: every interior row up to `through` holds its last level; alone on a cache line
  struct alignas(64) Progress {
    std::atomic<int> through{0};
  };
  std::vector<Progress> progress(static_cast<size_t>(asked));
  std::atomic<double>* const worker_time = worker_cpu_seconds();
#pragma omp parallel num_threads(asked) if (asked > 1)
  {
    const WorkerCpuTime timed(worker_time, omp_get_thread_num() != 0);
    const int workers = omp_get_num_threads(), w = omp_get_thread_num();
    const int first = w * steps / workers, count = (w + 1) * steps / workers - first;  // levels first+1 .. first+count
    for (int i = 1; count > 0 && i < n - 1 + count - 1; ++i) {
      // this worker's first level at row i needs the previous worker's last level at rows i-1, i, i+1
      if (w > 0 && i < n - 1)
        while (progress[w - 1].through.load(std::memory_order_acquire) < std::min(i + 1, n - 2)) std::this_thread::yield();
      for (int q = 0; q < count; ++q) {
        const int row = i - q, level = first + q + 1;
        if (row < 1 || row > n - 2) continue;
        double* into = level % 2 ? z_prev : z;
        const double* from = level % 2 ? z : z_prev;
        const std::ptrdiff_t offset = static_cast<std::ptrdiff_t>(row) * n;
        row_kernel(k, n, 1, n - 1, into + offset, from + offset);
      }
      if (i - count + 1 >= 1) progress[w].through.store(std::min(i - count + 1, n - 2), std::memory_order_release);
    }
  }
}

}  // namespace stepwise
