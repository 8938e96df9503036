// A PDE written as text (scenes/gray-scott.toml, model = "pde": its pointwise formula compiled once and applied at
// every node in one loop, models/pde.hpp) against the same right-hand side hand-written in C++ as a stencil loop
// over the periodic grid, at 256 x 256 nodes; and the interpreter beside both. The target: the compiled text within
// 1.2x the hand-written loop. Ratios printed after the table: text / hand-written, interpreted / hand-written; and
// the exact sparse Jacobian's cost in calls of f. Then the Newton matrix I - J of the same scene at 2 x 64^2 and
// 2 x 128^2 unknowns, one numeric factorisation by each sparse LU at hand, its pattern analysed before: KLU's
// refactorisation (what SUNDIALS' KLU solver repeats), UMFPACK's and Eigen's SparseLU, as ratios to UMFPACK's.
#include "models/pde.hpp"
#include "ratio_reporter.hpp"
#include "run/scene.hpp"
#include "solvers/blas_threads.hpp"

#include <Eigen/SparseLU>
#include <Eigen/UmfPackSupport>
#include <klu.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace {

constexpr int n = 256;

std::unique_ptr<stepwise::Model> gray_scott(bool compile, int points = n) {
  const auto scene = stepwise::load_scene(std::string(STEPWISE_SOURCE_DIR) + "/scenes/gray-scott.toml");
  return stepwise::make_pde(*scene.pde, {{"points", points}}, compile);
}

// the same f by hand: u' = Du lap(u) - u v^2 + F (1 - u), v' = Dv lap(v) + u v^2 - (F + k) v on the periodic grid,
// as one would write it for speed: a row's interior in one loop without wrapping (which the compiler vectorises),
// its two ends wrapped
void hand_written(const Eigen::VectorXd& y, Eigen::VectorXd& dydt, double h) {
  const double Du = 2e-5, Dv = 1e-5, F = 0.04, k = 0.06, inv_h2 = 1 / (h * h);
  const double* __restrict u = y.data();
  const double* __restrict v = y.data() + n * n;
  double* __restrict du = dydt.data();
  double* __restrict dv = dydt.data() + n * n;
  const auto node = [&](int c, int east, int west, int up, int down) {
    const double lap_u = (u[east] + u[west] + u[up] + u[down] - 4 * u[c]) * inv_h2;
    const double lap_v = (v[east] + v[west] + v[up] + v[down] - 4 * v[c]) * inv_h2;
    const double uvv = u[c] * v[c] * v[c];
    du[c] = Du * lap_u - uvv + F * (1 - u[c]);
    dv[c] = Dv * lap_v + uvv - (F + k) * v[c];
  };
  for (int j = 0; j < n; ++j) {
    const int up = (j + 1) % n * n - j * n, down = (j + n - 1) % n * n - j * n, row = j * n;
    node(row, row + 1, row + n - 1, row + up, row + down);
    for (int c = row + 1; c < row + n - 1; ++c) node(c, c + 1, c - 1, c + up, c + down);
    node(row + n - 1, row, row + n - 2, row + n - 1 + up, row + n - 1 + down);
  }
}

void rhs(benchmark::State& state, int which) {
  const auto model = gray_scott(which != 2);
  const Eigen::VectorXd y = model->initial_state();
  Eigen::VectorXd dydt(y.size());
  const double h = 0.5 / n;  // the scene's square is 0.5 wide
  for (auto _ : state) {
    if (which == 0) hand_written(y, dydt, h);
    else model->rhs(0, y, dydt);
    benchmark::DoNotOptimize(dydt.data());
  }
  state.counters["nodes"] = n * n;
}

void jacobian(benchmark::State& state) {
  const auto model = gray_scott(true);
  const Eigen::VectorXd y = model->initial_state();
  Eigen::SparseMatrix<double> J;
  for (auto _ : state) {
    model->as<stepwise::SparseJacobian>()->sparse_jacobian(0, y, J);
    benchmark::DoNotOptimize(J.valuePtr());
  }
  state.counters["nonzeros"] = static_cast<double>(J.nonZeros());
}

// I - J at the initial state (gamma h = 1: Gray-Scott's implicit steps at its patterns' pace, a step of a few
// time units, make it a few times that)
Eigen::SparseMatrix<double> newton_matrix(int points) {
  const auto model = gray_scott(true, points);
  Eigen::SparseMatrix<double> J, identity(model->size(), model->size());
  model->as<stepwise::SparseJacobian>()->sparse_jacobian(0, model->initial_state(), J);
  identity.setIdentity();
  Eigen::SparseMatrix<double> w = identity - J;
  w.makeCompressed();
  return w;
}

template <class Solver>
void factor_eigen(benchmark::State& state, int points) {
  Eigen::SparseMatrix<double> w = newton_matrix(points);
  Solver lu;
  lu.analyzePattern(w);
  for (auto _ : state) {
    lu.factorize(w);
    benchmark::DoNotOptimize(lu.info());
  }
  state.counters["unknowns"] = static_cast<double>(w.rows());
}

void factor_klu(benchmark::State& state, int points) {
  Eigen::SparseMatrix<double> w = newton_matrix(points);
  klu_common common;
  klu_defaults(&common);
  common.ordering = 0;  // AMD, as the SUNDIALS adapters set it
  const int rows = static_cast<int>(w.rows());
  klu_symbolic* symbolic = klu_analyze(rows, w.outerIndexPtr(), w.innerIndexPtr(), &common);
  klu_numeric* numeric = klu_factor(w.outerIndexPtr(), w.innerIndexPtr(), w.valuePtr(), symbolic, &common);
  for (auto _ : state) benchmark::DoNotOptimize(klu_refactor(w.outerIndexPtr(), w.innerIndexPtr(), w.valuePtr(), symbolic, numeric, &common));
  klu_free_numeric(&numeric, &common);
  klu_free_symbolic(&symbolic, &common);
  state.counters["unknowns"] = rows;
}

}  // namespace

int main(int argc, char** argv) {
  stepwise::keep_blas_on_this_thread();  // UMFPACK's BLAS as the product runs it
  // a cache of the bench's own, so the first model compiles and the timed ones load
  const auto cache = std::filesystem::temp_directory_path() / "stepwise-bench-pde-cache";
  ::setenv("STEPWISE_CACHE", cache.c_str(), 1);
  benchmark::RegisterBenchmark("gray_scott_256/hand_written", [](benchmark::State& s) { rhs(s, 0); });
  benchmark::RegisterBenchmark("gray_scott_256/text", [](benchmark::State& s) { rhs(s, 1); });
  benchmark::RegisterBenchmark("gray_scott_256/interpreted", [](benchmark::State& s) { rhs(s, 2); });
  benchmark::RegisterBenchmark("gray_scott_256/jacobian", jacobian);
  std::vector<std::pair<std::string, std::string>> ratios{{"gray_scott_256/text", "gray_scott_256/hand_written"},
                                                          {"gray_scott_256/interpreted", "gray_scott_256/hand_written"},
                                                          {"gray_scott_256/jacobian", "gray_scott_256/text"}};
  for (const int points : {64, 128}) {
    const std::string at = "gray_scott_" + std::to_string(points) + "/factor_";
    benchmark::RegisterBenchmark((at + "umfpack").c_str(), [points](benchmark::State& s) { factor_eigen<Eigen::UmfPackLU<Eigen::SparseMatrix<double>>>(s, points); })
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark((at + "klu_refactor").c_str(), [points](benchmark::State& s) { factor_klu(s, points); })->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark((at + "eigen_sparselu").c_str(), [points](benchmark::State& s) { factor_eigen<Eigen::SparseLU<Eigen::SparseMatrix<double>>>(s, points); })
        ->Unit(benchmark::kMillisecond);
    ratios.emplace_back(at + "klu_refactor", at + "umfpack");
    ratios.emplace_back(at + "eigen_sparselu", at + "umfpack");
  }
  const int code = stepwise::bench::run_with_ratios(argc, argv, ratios);
  std::filesystem::remove_all(cache);
  return code;
}
