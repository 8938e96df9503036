#include "distributed_lines.hpp"

#include "distributed_wave.hpp"
#include "kernels/wave_acceleration.hpp"

#include <arkode/arkode_arkstep.h>
#include <cvode/cvode.h>
#include <mpi.h>
#include <nvector/nvector_parallel.h>
#include <sundials/sundials_context.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <fmt/format.h>

#include <memory>
#include <type_traits>

namespace stepwise {

namespace {

struct ContextFree {
  void operator()(SUNContext c) const { SUNContext_Free(&c); }
};
struct VectorFree {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct SolverFree {
  void operator()(SUNNonlinearSolver s) const { SUNNonlinSolFree(s); }
};
struct CvodeFree {
  void operator()(void* mem) const { CVodeFree(&mem); }
};
struct ArkodeFree {
  void operator()(void* mem) const { ARKStepFree(&mem); }
};

// what f reaches through user_data: the grid, this rank's block and the halo it exchanges
struct Lines {
  DistributedWave* grid;
  DistributedWave::Block block;
  int n = 0;  // the whole grid's points per side
  double c2 = 0, mu = 0;
  long rhs_evals = 0;
};

// local state: the block's z (rows x cols, row-major), then its v
int rhs(sunrealtype, N_Vector y, N_Vector ydot, void* user_data) {
  Lines& L = *static_cast<Lines*>(user_data);
  ++L.rhs_evals;
  const int r = L.block.rows, c = L.block.cols, s = L.grid->stride();
  const double* z = N_VGetArrayPointer(y);
  const double* v = z + static_cast<std::ptrdiff_t>(r) * c;
  double* dz = N_VGetArrayPointer(ydot);
  double* dv = dz + static_cast<std::ptrdiff_t>(r) * c;
  double* halo = L.grid->level();
  for (int a = 0; a < r; ++a)
    for (int b = 0; b < c; ++b) halo[(a + 1) * s + b + 1] = z[a * c + b];
  L.grid->exchange();
  for (int a = 0; a < r; ++a)
    for (int b = 0; b < c; ++b) {
      const int i = L.block.row0 + a, j = L.block.col0 + b, k = a * c + b;
      const bool interior = i > 0 && i < L.n - 1 && j > 0 && j < L.n - 1;
      dz[k] = v[k];
      dv[k] = interior ? wave_acceleration(L.c2, L.mu, neighbour_sum(halo, (a + 1) * s + b + 1, s), z[k], v[k]) : 0.0;
    }
  return 0;
}

}  // namespace

DistributedLinesRun lines_distributed(std::string_view method, const WaveGridView& view, const Eigen::VectorXd& y0, double t_end, double rtol,
                                      double atol) {
  const int n = view.points;
  DistributedWave grid(n, n, WaveCoefficients{});
  Lines lines{&grid, grid.block(), n, view.c * view.c / (view.spacing * view.spacing), view.mu};
  const auto& B = lines.block;
  const long local = 2L * B.rows * B.cols, global = 2L * n * n;
  DistributedLinesRun run;
  const auto failed = [&](std::string_view call, long code) {
    run.failure = fmt::format("{}: {} failed with code {}", method, call, code);
    return run;
  };
  if (method != "cvode-adams" && method != "arkode-erk-dormand-prince54") {
    run.failure = fmt::format("{}: not run on the distributed grid (cvode-adams and arkode-erk-dormand-prince54 are)", method);
    return run;
  }
  SUNContext raw_context = nullptr;
  if (const int code = SUNContext_Create(nullptr, &raw_context)) return failed("SUNContext_Create", code);
  std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextFree> context(raw_context);
  std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorFree> y(N_VNew_Parallel(MPI_COMM_WORLD, local, global, context.get()));
  if (!y) return failed("N_VNew_Parallel", 0);
  double* yl = N_VGetArrayPointer(y.get());
  const Eigen::Index cells = static_cast<Eigen::Index>(n) * n;
  for (int a = 0; a < B.rows; ++a)
    for (int b = 0; b < B.cols; ++b) {
      const Eigen::Index g = static_cast<Eigen::Index>(B.row0 + a) * n + B.col0 + b;
      yl[a * B.cols + b] = y0[g];
      yl[static_cast<long>(B.rows) * B.cols + a * B.cols + b] = y0[cells + g];
    }
  double t = 0;
  if (method == "cvode-adams") {
    // as the cvode-adams method sets it up (solvers/methods/cvode.cpp): Adams, fixed-point iteration
    std::unique_ptr<void, CvodeFree> mem(CVodeCreate(CV_ADAMS, context.get()));
    if (!mem) return failed("CVodeCreate", 0);
    if (const int code = CVodeInit(mem.get(), rhs, 0.0, y.get())) return failed("CVodeInit", code);
    if (const int code = CVodeSetUserData(mem.get(), &lines)) return failed("CVodeSetUserData", code);
    if (const int code = CVodeSStolerances(mem.get(), rtol, atol)) return failed("CVodeSStolerances", code);
    if (const int code = CVodeSetMaxNumSteps(mem.get(), 5'000'000)) return failed("CVodeSetMaxNumSteps", code);
    std::unique_ptr<std::remove_pointer_t<SUNNonlinearSolver>, SolverFree> fixed_point(SUNNonlinSol_FixedPoint(y.get(), 0, context.get()));
    if (const int code = CVodeSetNonlinearSolver(mem.get(), fixed_point.get())) return failed("CVodeSetNonlinearSolver", code);
    if (const int code = CVode(mem.get(), t_end, y.get(), &t, CV_NORMAL); code < 0) return failed("CVode", code);
    CVodeGetNumSteps(mem.get(), &run.steps);
  } else {
    // as the arkode-erk methods set it up (solvers/methods/arkode.cpp): ARKStep with no implicit part, the table
    // by number (ERKStep mistakes some tables for first-same-as-last: docs/findings.md)
    std::unique_ptr<void, ArkodeFree> mem(ARKStepCreate(rhs, nullptr, 0.0, y.get(), context.get()));
    if (!mem) return failed("ARKStepCreate", 0);
    if (const int code = ARKStepSetUserData(mem.get(), &lines)) return failed("ARKStepSetUserData", code);
    if (const int code = ARKStepSetTableNum(mem.get(), ARKODE_DIRK_NONE, ARKODE_DORMAND_PRINCE_7_4_5)) return failed("ARKStepSetTableNum", code);
    if (const int code = ARKStepSStolerances(mem.get(), rtol, atol)) return failed("ARKStepSStolerances", code);
    if (const int code = ARKStepSetMaxNumSteps(mem.get(), 5'000'000)) return failed("ARKStepSetMaxNumSteps", code);
    // the step lands on the output time, as the adapter's do (ARKODE's interpolant is of lower order)
    if (const int code = ARKStepSetStopTime(mem.get(), t_end)) return failed("ARKStepSetStopTime", code);
    if (const int code = ARKStepEvolve(mem.get(), t_end, y.get(), &t, ARK_NORMAL); code < 0) return failed("ARKStepEvolve", code);
    ARKStepGetNumSteps(mem.get(), &run.steps);
  }
  run.rhs_evals = lines.rhs_evals;
  std::vector<double> z(yl, yl + static_cast<long>(B.rows) * B.cols), v(yl + static_cast<long>(B.rows) * B.cols, yl + local);
  std::vector<double> zg = grid.gather(z), vg = grid.gather(v);
  if (!zg.empty()) {
    run.y = std::move(zg);
    run.y.insert(run.y.end(), vg.begin(), vg.end());
  }
  return run;
}

}  // namespace stepwise
