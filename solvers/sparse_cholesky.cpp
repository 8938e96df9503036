#include "sparse_cholesky.hpp"

#include "blas_threads.hpp"

#include <cholmod.h>
#include <fmt/format.h>
#include <omp.h>
#include <pthread.h>

#include <algorithm>
#include <csignal>
#include <iterator>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <vector>

namespace stepwise {

namespace {

// Debian's CHOLMOD opens OpenMP parallel regions of a fixed 4 threads (CHOLMOD_OMP_NUM_THREADS, compiled in)
// to copy and clear its arrays, whatever omp_set_num_threads says; on 2 cores their start-up and spinning
// cost more than the copies (measured: a factorisation's wall time was twice its CPU time). While a CHOLMOD
// call runs, parallel regions are made inactive (one thread), and the setting is restored after it.
class SerialOpenMP {
 public:
  SerialOpenMP() : levels_(omp_get_max_active_levels()) { omp_set_max_active_levels(0); }
  ~SerialOpenMP() { omp_set_max_active_levels(levels_); }
  SerialOpenMP(const SerialOpenMP&) = delete;
  SerialOpenMP& operator=(const SerialOpenMP&) = delete;

 private:
  int levels_;
};

// METIS (through GKlib) installs handlers of its own for SIGTERM and SIGABRT for the length of each call and
// puts back the previous ones from thread-local slots: two threads in METIS at once put back each other's, which
// left METIS's handler (a longjmp to a thread-local jump buffer that other threads never set) installed for good,
// and the next SIGTERM crashed the process by SIGSEGV in __longjmp_chk instead of ending it cleanly
// (run/interrupt.hpp). So: one METIS call at a time in the process, the dispositions of the signals it touches
// and the ones an interruption comes by saved before and put back after, and those signals blocked in the
// calling thread meanwhile. A signal taken by another thread during the call still meets METIS's handler: the
// reason `cheaper` calls METIS only for large systems (metis_worth_trying), which the report never analyses
class MetisCall {
 public:
  MetisCall() : lock_(mutex()) {
    sigset_t set;
    sigemptyset(&set);
    for (size_t k = 0; k < std::size(signals); ++k) {
      ::sigaction(signals[k], nullptr, &saved_[k]);
      sigaddset(&set, signals[k]);
    }
    ::pthread_sigmask(SIG_BLOCK, &set, &mask_);
  }
  ~MetisCall() {
    for (size_t k = 0; k < std::size(signals); ++k) ::sigaction(signals[k], &saved_[k], nullptr);
    ::pthread_sigmask(SIG_SETMASK, &mask_, nullptr);
  }
  MetisCall(const MetisCall&) = delete;
  MetisCall& operator=(const MetisCall&) = delete;

 private:
  static constexpr int signals[] = {SIGTERM, SIGINT, SIGHUP, SIGABRT};
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  struct sigaction saved_[std::size(signals)] {};
  sigset_t mask_{};
};

}  // namespace

struct SparseCholesky::Impl {
  cholmod_common common{};
  cholmod_sparse* lower = nullptr;   // the lower triangle, values refreshed at each factorisation
  cholmod_factor* factor = nullptr;
  mutable cholmod_dense* b = nullptr;
  mutable cholmod_dense* x = nullptr;
  mutable cholmod_dense* y = nullptr;  // cholmod_solve2's workspace
  mutable cholmod_dense* e = nullptr;
  std::vector<Eigen::Index> source;  // for each entry of `lower`, its index in the Eigen matrix's values
  CholeskyAnalysis analysis;
  bool factored = false;

  Impl() {
    keep_blas_on_this_thread();
    cholmod_start(&common);
    common.print = 0;     // failures are reported through the status, in words, by the caller
    // supernodes amalgamated more than CHOLMOD's default (4, 16, 48 columns at most before it takes no explicit
    // zero): each supernode opens Debian's CHOLMOD's OpenMP regions, each region ends with a futex call even with one
    // thread, and a supernode's dense kernels run faster wide; wider still (32, 128, 512) is slower again, the
    // explicit zeros' work (measured: docs/performance-cloth.md)
    common.nrelax[0] = 16;
    common.nrelax[1] = 64;
    common.nrelax[2] = 256;
    common.final_ll = 1;  // L L^T also on the simplicial path, whose default L D L^T would factor an indefinite
                          // matrix without a word (negative D): the step needs it positive definite
  }
  ~Impl() {
    release();
    cholmod_finish(&common);
  }
  void release() {
    cholmod_free_dense(&b, &common);
    cholmod_free_dense(&x, &common);
    cholmod_free_dense(&y, &common);
    cholmod_free_dense(&e, &common);
    cholmod_free_factor(&factor, &common);
    cholmod_free_sparse(&lower, &common);
  }
  std::string status(std::string_view call) const {
    return fmt::format("{} failed (CHOLMOD status {})", call, common.status);
  }
};

SparseCholesky::SparseCholesky() : impl_(std::make_unique<Impl>()) {}
SparseCholesky::~SparseCholesky() = default;

const CholeskyAnalysis& SparseCholesky::analysis() const { return impl_->analysis; }
bool SparseCholesky::factored() const { return impl_->factored; }

std::string SparseCholesky::analyze(const Eigen::SparseMatrix<double>& a, Ordering ordering) {
  const SerialOpenMP serial;
  Impl& m = *impl_;
  m.release();
  m.factored = false;
  const Eigen::Index n = a.rows();
  if (a.cols() != n || !a.isCompressed()) throw std::invalid_argument("SparseCholesky::analyze: a compressed square matrix is needed");
  m.source.clear();
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index k = a.outerIndexPtr()[j]; k < a.outerIndexPtr()[j + 1]; ++k)
      if (a.innerIndexPtr()[k] <= j) m.source.push_back(k);
  m.lower = cholmod_allocate_sparse(static_cast<size_t>(n), static_cast<size_t>(n), m.source.size(), 1, 1, 1, CHOLMOD_REAL, &m.common);
  if (!m.lower) return m.status("cholmod_allocate_sparse");
  auto* column = static_cast<int*>(m.lower->p);
  auto* row = static_cast<int*>(m.lower->i);
  size_t k = 0;
  for (Eigen::Index j = 0; j < n; ++j) {
    column[j] = static_cast<int>(k);
    for (Eigen::Index s = a.outerIndexPtr()[j]; s < a.outerIndexPtr()[j + 1]; ++s)
      if (a.innerIndexPtr()[s] <= j) row[k++] = a.innerIndexPtr()[s];
  }
  column[n] = static_cast<int>(k);

  const auto analyse_with = [&](int method) -> cholmod_factor* {
    m.common.nmethods = 1;
    m.common.method[0].ordering = method;
    m.common.postorder = 1;
    std::optional<MetisCall> metis;
    if (method == CHOLMOD_METIS) metis.emplace();
    return cholmod_analyze(m.lower, &m.common);
  };
  m.analysis = {};
  if (ordering == Ordering::cheaper && n < metis_worth_trying) ordering = Ordering::amd;
  if (ordering == Ordering::cheaper) {
    cholmod_factor* amd = analyse_with(CHOLMOD_AMD);
    if (!amd) return m.status("cholmod_analyze (AMD)");
    const double amd_flops = m.common.fl;
    cholmod_factor* metis = analyse_with(CHOLMOD_METIS);
    if (!metis) {
      cholmod_free_factor(&amd, &m.common);
      return m.status("cholmod_analyze (METIS)");
    }
    const double metis_flops = m.common.fl;
    const bool metis_cheaper = metis_flops < amd_flops;
    m.factor = metis_cheaper ? metis : amd;
    cholmod_free_factor(metis_cheaper ? &amd : &metis, &m.common);
    m.analysis.ordering = metis_cheaper ? "metis" : "amd";
    m.analysis.flops = std::min(amd_flops, metis_flops);
  } else {
    m.factor = analyse_with(ordering == Ordering::metis ? CHOLMOD_METIS : CHOLMOD_AMD);
    if (!m.factor) return m.status("cholmod_analyze");
    m.analysis.ordering = ordering == Ordering::metis ? "metis" : "amd";
    m.analysis.flops = m.common.fl;
  }
  // entries of L as the analysis counts them (the column counts)
  const auto* counts = static_cast<const int*>(m.factor->ColCount);
  for (Eigen::Index j = 0; j < n; ++j) m.analysis.factor_nonzeros += counts[j];
  return {};
}

std::string SparseCholesky::factorize(const Eigen::SparseMatrix<double>& a) {
  const SerialOpenMP serial;
  Impl& m = *impl_;
  if (!m.factor) throw std::logic_error("SparseCholesky::factorize before analyze");
  auto* values = static_cast<double*>(m.lower->x);
  const double* from = a.valuePtr();
  for (size_t k = 0; k < m.source.size(); ++k) values[k] = from[m.source[k]];
  const int ok = cholmod_factorize(m.lower, m.factor, &m.common);
  m.factored = false;
  if (m.common.status == CHOLMOD_NOT_POSDEF)
    return fmt::format("cholmod_factorize: matrix not positive definite (column {} of {}, CHOLMOD status {})", m.factor->minor,
                       m.factor->n, m.common.status);
  if (!ok || m.common.status < 0) return m.status("cholmod_factorize");
  m.factored = true;
  return {};
}

std::string SparseCholesky::solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const {
  const SerialOpenMP serial;
  Impl& m = *impl_;
  if (!m.factored) throw std::logic_error("SparseCholesky::solve without a factor");
  const auto n = static_cast<size_t>(b.rows()), k = static_cast<size_t>(b.cols());
  if (!m.b || m.b->ncol != k) {
    cholmod_free_dense(&m.b, &m.common);
    m.b = cholmod_allocate_dense(n, k, n, CHOLMOD_REAL, &m.common);
    if (!m.b) return m.status("cholmod_allocate_dense");
  }
  std::copy(b.data(), b.data() + b.size(), static_cast<double*>(m.b->x));
  if (!cholmod_solve2(CHOLMOD_A, m.factor, m.b, nullptr, &m.x, nullptr, &m.y, &m.e, &m.common))
    return m.status("cholmod_solve2");
  x.resize(b.rows(), b.cols());
  const auto* result = static_cast<const double*>(m.x->x);
  std::copy(result, result + b.size(), x.data());
  return {};
}

}  // namespace stepwise
