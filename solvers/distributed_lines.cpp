#include "distributed_lines.hpp"

#include "distributed_wave.hpp"

#include "sundials_support.hpp"

#include <arkode/arkode_arkstep.h>
#include <cvode/cvode.h>
#include <mpi.h>
#include <nvector/nvector_parallel.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <fmt/format.h>

#include <memory>

namespace stepwise {

namespace {

using sundials::ContextPtr, sundials::VectorPtr, sundials::LinSolPtr, sundials::NonlinSolPtr, sundials::CvodePtr, sundials::ArkodePtr;

// what f reaches through user_data: the grid, this rank's block and the halo it exchanges
struct Lines {
  DistributedWave* grid;
  WaveGridView view;
  long rhs_evals = 0;
};

// f on the local state (the block's z, then its v), or a part of it as the model splits it for IMEX
// (distributed_wave.hpp's block_rhs: `stiff` z' = v and c^2 Lap z, `damping` -mu v)
template <bool stiff, bool damping>
int rhs(sunrealtype, N_Vector y, N_Vector ydot, void* user_data) {
  Lines& L = *static_cast<Lines*>(user_data);
  ++L.rhs_evals;
  block_rhs(*L.grid, L.view, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), stiff, damping);
  return 0;
}

}  // namespace

DistributedLinesRun lines_distributed(const Method& method, const WaveGridView& view, const Eigen::VectorXd& y0, double t_end, double rtol,
                                      double atol) {
  const int n = view.points;
  DistributedWave grid(n, n, WaveCoefficients{});
  Lines lines{&grid, view};
  const auto B = grid.block();
  const long local = 2L * B.rows * B.cols, global = 2L * n * n;
  DistributedLinesRun run;
  const auto failed = [&](std::string_view call, long code) {
    run.failure = fmt::format("{}: {} failed with code {}", method.name, call, code);
    return run;
  };
  const bool cvode = method.on_ranks == OnRanks::cvode_adams || method.on_ranks == OnRanks::cvode_bdf;
  // an ARKODE method's tables, from its family's own list (solvers/methods/arkode.cpp)
  const auto tables = sundials::arkode_tables(method.on_ranks == OnRanks::arkode ? method.name : std::string_view());
  if (!cvode && !tables) {
    run.failure = fmt::format("{}: not run on the distributed grid (cvode-adams, cvode-bdf and the arkode-* methods are)", method.name);
    return run;
  }
  SUNContext raw_context = nullptr;
  if (const int code = SUNContext_Create(nullptr, &raw_context)) return failed("SUNContext_Create", code);
  ContextPtr context(raw_context);
  VectorPtr y(N_VNew_Parallel(MPI_COMM_WORLD, local, global, context.get()));
  if (!y) return failed("N_VNew_Parallel", 0);
  double* yl = N_VGetArrayPointer(y.get());
  const Eigen::Index cells = static_cast<Eigen::Index>(n) * n;
  for (int a = 0; a < B.rows; ++a)
    for (int b = 0; b < B.cols; ++b) {
      const Eigen::Index g = static_cast<Eigen::Index>(B.row0 + a) * n + B.col0 + b;
      yl[a * B.cols + b] = y0[g];
      yl[static_cast<long>(B.rows) * B.cols + a * B.cols + b] = y0[cells + g];
    }
  // Newton's linear systems: GMRES (SPGMR), matrix-free (J v by SUNDIALS' difference quotient, one f each),
  // unpreconditioned; its dot products are sums over the ranks, as the norms are. One process uses KLU on the
  // sparse Jacobian instead: the same method, another linear solver, so the runs agree to the tolerance
  const auto gmres = [&]() { return LinSolPtr(SUNLinSol_SPGMR(y.get(), SUN_PREC_NONE, 0, context.get())); };
  double t = 0;
  if (cvode) {
    // as cvode-adams and cvode-bdf set it up (solvers/methods/cvode.cpp): Adams with fixed-point iteration,
    // BDF with Newton
    const bool bdf = method.on_ranks == OnRanks::cvode_bdf;
    CvodePtr mem(CVodeCreate(bdf ? CV_BDF : CV_ADAMS, context.get()));
    if (!mem) return failed("CVodeCreate", 0);
    if (const int code = CVodeInit(mem.get(), rhs<true, true>, 0.0, y.get())) return failed("CVodeInit", code);
    if (const int code = CVodeSetUserData(mem.get(), &lines)) return failed("CVodeSetUserData", code);
    if (const int code = CVodeSStolerances(mem.get(), rtol, atol)) return failed("CVodeSStolerances", code);
    if (const int code = CVodeSetMaxNumSteps(mem.get(), 5'000'000)) return failed("CVodeSetMaxNumSteps", code);
    NonlinSolPtr fixed_point;
    LinSolPtr linear;
    if (bdf) {
      linear = gmres();
      if (!linear) return failed("SUNLinSol_SPGMR", 0);
      if (const int code = CVodeSetLinearSolver(mem.get(), linear.get(), nullptr)) return failed("CVodeSetLinearSolver", code);
    } else {
      fixed_point.reset(SUNNonlinSol_FixedPoint(y.get(), 0, context.get()));
      if (const int code = CVodeSetNonlinearSolver(mem.get(), fixed_point.get())) return failed("CVodeSetNonlinearSolver", code);
    }
    if (const int code = CVode(mem.get(), t_end, y.get(), &t, CV_NORMAL); code < 0) return failed("CVode", code);
    CVodeGetNumSteps(mem.get(), &run.steps);
  } else {
    // as the arkode-* methods set it up (solvers/methods/arkode.cpp): ARKStep with the tables by number (ERKStep
    // mistakes some tables for first-same-as-last: docs/findings.md); a DIRK method's implicit part the whole f,
    // an IMEX method's the model's stiff part (z' = v and the Laplacian, linear: one Newton iteration a stage)
    const bool explicit_only = tables->dirk == ARKODE_DIRK_NONE, implicit_only = tables->erk == ARKODE_ERK_NONE;
    const ARKRhsFn fe = explicit_only ? rhs<true, true> : implicit_only ? nullptr : rhs<false, true>;
    const ARKRhsFn fi = explicit_only ? nullptr : implicit_only ? rhs<true, true> : rhs<true, false>;
    ArkodePtr mem(ARKStepCreate(fe, fi, 0.0, y.get(), context.get()));
    if (!mem) return failed("ARKStepCreate", 0);
    if (const int code = ARKStepSetUserData(mem.get(), &lines)) return failed("ARKStepSetUserData", code);
    if (const int code = ARKStepSetTableNum(mem.get(), tables->dirk, tables->erk)) return failed("ARKStepSetTableNum", code);
    if (const int code = ARKStepSStolerances(mem.get(), rtol, atol)) return failed("ARKStepSStolerances", code);
    if (const int code = ARKStepSetMaxNumSteps(mem.get(), 5'000'000)) return failed("ARKStepSetMaxNumSteps", code);
    LinSolPtr linear;
    if (!explicit_only) {
      linear = gmres();
      if (!linear) return failed("SUNLinSol_SPGMR", 0);
      if (const int code = ARKStepSetLinearSolver(mem.get(), linear.get(), nullptr)) return failed("ARKStepSetLinearSolver", code);
      if (!implicit_only)
        if (const int code = ARKStepSetLinear(mem.get(), 0)) return failed("ARKStepSetLinear", code);
    }
    // the step lands on the output time, as the adapter's do (ARKODE's interpolant is of lower order)
    if (const int code = ARKStepSetStopTime(mem.get(), t_end)) return failed("ARKStepSetStopTime", code);
    if (const int code = ARKStepEvolve(mem.get(), t_end, y.get(), &t, ARK_NORMAL); code < 0) return failed("ARKStepEvolve", code);
    ARKStepGetNumSteps(mem.get(), &run.steps);
  }
  run.rhs_evals = lines.rhs_evals;
  const Eigen::VectorXd whole = grid.gather_state(Eigen::Map<const Eigen::VectorXd>(yl, local));
  run.y.assign(whole.data(), whole.data() + whole.size());
  return run;
}

}  // namespace stepwise
