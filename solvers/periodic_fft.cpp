// FFTW's types stay here: plans by size, made once under a lock (the planner is not thread-safe), executed
// on the callers' arrays (the new-array execute functions are)
#include "periodic_fft.hpp"

#include <fftw3.h>

#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>

namespace stepwise {

namespace {

struct Plans {
  fftw_plan forward = nullptr, inverse = nullptr;
};

// the plans of every size used, destroyed at exit with FFTW's own planner state (fftw_cleanup), so that a leak
// checker sees nothing of FFTW's left (an interrupted run leaves by _exit, without destructors: no thread is
// still transforming when they run)
struct PlanCache {
  std::map<int, Plans> plans;
  ~PlanCache() {
    for (auto& [n, p] : plans) {
      fftw_destroy_plan(p.forward);
      fftw_destroy_plan(p.inverse);
    }
    fftw_cleanup();
  }
};

// FFTW_ESTIMATE: the plan chosen by FFTW's model, the same in every process. FFTW_MEASURE chose by timing
// candidates, and under a different load a different algorithm, which rounds differently: a 2-rank report's
// fluid viscosity CSV differed from one process's in the 15th digit (mpi_ranks). Measured, ESTIMATE's plans
// cost 1.3x MEASURE's at 256^2 (a forward transform 0.194 -> 0.254 ms), the fluid's f 1.25x, a Stable Fluids
// step 1.06x. FFTW_UNALIGNED lets the plans run on any caller's arrays (std::vector's are 16-byte aligned,
// FFTW's own 32 or 64)
const Plans& plans_for(int n) {
  static std::mutex lock;
  static PlanCache cache;
  auto& plans = cache.plans;
  std::lock_guard guard(lock);
  auto [it, added] = plans.try_emplace(n);
  if (added) {
    const int half = n / 2 + 1;
    std::unique_ptr<double, decltype(&fftw_free)> grid(fftw_alloc_real(static_cast<size_t>(n) * n), fftw_free);
    std::unique_ptr<fftw_complex, decltype(&fftw_free)> modes(fftw_alloc_complex(static_cast<size_t>(n) * half), fftw_free);
    const unsigned flags = FFTW_ESTIMATE | FFTW_UNALIGNED;
    it->second.forward = fftw_plan_dft_r2c_2d(n, n, grid.get(), modes.get(), flags);
    it->second.inverse = fftw_plan_dft_c2r_2d(n, n, modes.get(), grid.get(), flags);
    if (!it->second.forward || !it->second.inverse) {
      plans.erase(it);
      throw std::runtime_error("fftw_plan_dft_r2c_2d/c2r_2d: no plan for a " + std::to_string(n) + "^2 grid");
    }
  }
  return it->second;
}

}  // namespace

std::string PeriodicFft::library_version() { return fftw_version; }

PeriodicFft::PeriodicFft(int n, double length) : n_(n), half_(n / 2 + 1), length_(length) {
  if (n < 2) throw std::invalid_argument("PeriodicFft: at least 2 points per side");
  const double unit = 2 * std::numbers::pi / length;
  const auto wavenumber = [&](int index) { return index <= n / 2 ? index : index - n; };
  const bool even = n % 2 == 0;
  k_.resize(half_);
  k2_col_.resize(half_);
  for (int c = 0; c < half_; ++c) {
    const double k = unit * c;
    k_[c] = even && c == n / 2 ? 0.0 : k;
    k2_col_[c] = k * k;
  }
  k_row_.resize(n);
  k2_row_.resize(n);
  for (int r = 0; r < n; ++r) {
    const double k = unit * wavenumber(r);
    k_row_[r] = even && r == n / 2 ? 0.0 : k;
    k2_row_[r] = k * k;
  }
  keep_.resize(n + half_);
  for (int r = 0; r < n; ++r) keep_[r] = std::abs(wavenumber(r)) <= largest_kept(n);
  for (int c = 0; c < half_; ++c) keep_[n + c] = c <= largest_kept(n);
  plans_ = &plans_for(n);
}

void PeriodicFft::forward(const double* grid, Complex* modes) const {
  fftw_execute_dft_r2c(static_cast<const Plans*>(plans_)->forward, const_cast<double*>(grid), reinterpret_cast<fftw_complex*>(modes));
}

void PeriodicFft::inverse(Complex* modes, double* grid) const {
  fftw_execute_dft_c2r(static_cast<const Plans*>(plans_)->inverse, reinterpret_cast<fftw_complex*>(modes), grid);
  const double scale = 1.0 / (static_cast<double>(n_) * n_);
  for (int i = 0; i < n_ * n_; ++i) grid[i] *= scale;
}

void PeriodicFft::dealias(Complex* a) const {
  for (int m = 0; m < modes(); ++m)
    if (!kept(m)) a[m] = 0;
}

void PeriodicFft::diffuse(Complex* a, double c) const {
  for (int m = 0; m < modes(); ++m) a[m] /= 1 + c * k2(m);
}

void PeriodicFft::project(Complex* u, Complex* v) const {
  for (int m = 0; m < modes(); ++m) {
    const double x = kx(m), y = ky(m), kk = x * x + y * y;
    if (kk == 0) continue;
    const Complex along = (x * u[m] + y * v[m]) / kk;
    u[m] -= x * along;
    v[m] -= y * along;
  }
}

}  // namespace stepwise
