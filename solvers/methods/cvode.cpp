// cvode-adams, cvode-bdf: SUNDIALS CVODE (6.4), always adaptive (SUNDIALS' types stay in this file).
//
// Pitfalls handled here:
// - Adams with CVODE's default Newton solver and no linear solver fails (CVode returns -13,
//   CV_LINIT_FAIL): Adams gets SUNNonlinSol_FixedPoint, BDF gets Newton with a direct linear solver;
// - CVodeGetNumRhsEvals misses the calls made for difference-quotient Jacobians and is reset by
//   CVodeReInit: every call of f is counted in the CountedSystem wrapper instead;
// - events use CVODE's rootfinding (CVodeRootInit, CVodeSetRootDirection); after a root the handler changes
//   the state and CVodeReInit restarts there, which resets CVODE's counters, so they are summed across
//   re-initialisations; a root exactly at the restart point is not reported again by CVODE;
// - a right-hand side that produces non-finite values returns 1 (recoverable): CVODE cuts the step,
//   and a run that still fails is reported as diverged, not as a solver failure.
#include "solvers/method.hpp"

#include "solvers/run_support.hpp"

#include <cvode/cvode.h>
#include <cvode/cvode_proj.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cstdlib>

namespace stepwise {
namespace {

// RAII for every SUNDIALS handle
struct ContextFree { void operator()(SUNContext c) const { SUNContext_Free(&c); } };
struct VectorFree { void operator()(_generic_N_Vector* v) const { N_VDestroy(v); } };
struct MatrixFree { void operator()(_generic_SUNMatrix* m) const { SUNMatDestroy(m); } };
struct LinSolFree { void operator()(_generic_SUNLinearSolver* s) const { SUNLinSolFree(s); } };
struct NonlinSolFree { void operator()(_generic_SUNNonlinearSolver* s) const { SUNNonlinSolFree(s); } };
struct CvodeFree { void operator()(void* mem) const { CVodeFree(&mem); } };
using ContextPtr = std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextFree>;
using VectorPtr = std::unique_ptr<_generic_N_Vector, VectorFree>;
using MatrixPtr = std::unique_ptr<_generic_SUNMatrix, MatrixFree>;
using LinSolPtr = std::unique_ptr<_generic_SUNLinearSolver, LinSolFree>;
using NonlinSolPtr = std::unique_ptr<_generic_SUNNonlinearSolver, NonlinSolFree>;
using CvodePtr = std::unique_ptr<void, CvodeFree>;

std::string flag_name(long flag) {
  char* name = CVodeGetReturnFlagName(flag);
  std::string s = name ? name : "unknown";
  std::free(name);
  return s;
}

// what CVODE's C callbacks reach through user_data
struct Callbacks {
  const CountedSystem* system;
  bool non_finite = false;         // f produced a non-finite value: the run has blown up
  std::string last_error;          // CVODE's own message for the last failure
  Eigen::MatrixXd jac;             // dense df/dy scratch (n x n), sized by the first dense Jacobian call
  Eigen::SparseMatrix<double> sparse_jac;  // sparse df/dy scratch, fixed pattern
  Eigen::VectorXd projected;       // projection scratch
};

int cvode_rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data) {
  auto& c = *static_cast<Callbacks*>(user_data);
  const auto n = static_cast<Eigen::Index>(N_VGetLength(y));
  Eigen::Map<Eigen::VectorXd> out(N_VGetArrayPointer(ydot), n);
  c.system->rhs(t, Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(y), n), out);
  if (out.allFinite()) return 0;
  c.non_finite = true;
  return 1;
}

int cvode_dense_jacobian(sunrealtype t, N_Vector y, N_Vector, SUNMatrix J, void* user_data, N_Vector, N_Vector, N_Vector) {
  auto& c = *static_cast<Callbacks*>(user_data);
  const auto n = static_cast<Eigen::Index>(N_VGetLength(y));
  c.jac.resize(n, n);
  c.system->jacobian(t, Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(y), n), c.jac);
  ++c.system->stats().jac_evals;
  // SUNDIALS dense matrices are column-major, like Eigen's default
  Eigen::Map<Eigen::MatrixXd>(SUNDenseMatrix_Data(J), n, n) = c.jac;
  return c.jac.allFinite() ? 0 : 1;
}

// CVODE forms I - gamma J in place with SUNMatScaleAddI_Sparse, which in SUNDIALS 6.4 rebuilds the whole
// matrix, column by column, for every missing diagonal entry: measured here, a particle system's Jacobian
// (no diagonal in its position rows) took 226 s for 16 000 particles, growing as n^2. Explicit zeros on the
// diagonal make the pattern complete and the setup linear.
void with_diagonal(Eigen::SparseMatrix<double>& J) {
  Eigen::SparseMatrix<double> zero(J.rows(), J.cols());
  zero.setIdentity();
  zero.coeffs().setZero();
  J = J + zero;
  J.makeCompressed();
}

int cvode_sparse_jacobian(sunrealtype t, N_Vector y, N_Vector, SUNMatrix J, void* user_data, N_Vector, N_Vector, N_Vector) {
  auto& c = *static_cast<Callbacks*>(user_data);
  const auto n = static_cast<Eigen::Index>(N_VGetLength(y));
  c.system->sparse_jacobian(t, Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(y), n), c.sparse_jac);
  ++c.system->stats().jac_evals;
  with_diagonal(c.sparse_jac);
  const auto nnz = c.sparse_jac.nonZeros();
  if (nnz > SUNSparseMatrix_NNZ(J)) SUNSparseMatrix_Reallocate(J, nnz);
  std::copy_n(c.sparse_jac.outerIndexPtr(), n + 1, SUNSparseMatrix_IndexPointers(J));
  std::copy_n(c.sparse_jac.innerIndexPtr(), nnz, SUNSparseMatrix_IndexValues(J));
  std::copy_n(c.sparse_jac.valuePtr(), nnz, SUNSparseMatrix_Data(J));
  return 0;
}

int cvode_roots(sunrealtype t, N_Vector y, sunrealtype* gout, void* user_data) {
  const auto& c = *static_cast<Callbacks*>(user_data);
  const auto n = static_cast<Eigen::Index>(N_VGetLength(y));
  const Eigen::VectorXd state = Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(y), n);
  const auto events = c.system->events();
  for (size_t i = 0; i < events.size(); ++i) gout[i] = events[i].g(t, state);
  return 0;
}

// CVODE's projection: corr takes ycur onto the system's manifold (the error estimate is not projected)
int cvode_projection(sunrealtype, N_Vector ycur, N_Vector corr, sunrealtype, N_Vector, void* user_data) {
  auto& c = *static_cast<Callbacks*>(user_data);
  const auto n = static_cast<Eigen::Index>(N_VGetLength(ycur));
  const Eigen::Map<const Eigen::VectorXd> y(N_VGetArrayPointer(ycur), n);
  c.projected = y;
  c.system->project(c.projected);
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(corr), n) = c.projected - y;
  return 0;
}

void cvode_error_handler(int, const char* module, const char* function, char* msg, void* user_data) {
  static_cast<Callbacks*>(user_data)->last_error = fmt::format("{}:{}: {}", module, function, msg);
}

class CvodeIntegrator final : public Integrator {
 public:
  CvodeIntegrator(std::string method, bool bdf, StepControl control)
      : method_(std::move(method)), bdf_(bdf), control_(control) {}

  RunResult integrate(const OdeSystem& system, double t0, const Eigen::VectorXd& y0,
                      std::span<const double> t_out) const override {
    RunResult result = begin_run(t0, y0);
    const double start = thread_cpu_seconds();
    CountedSystem counted(system, result.stats);
    const int n = system.size();
    Callbacks callbacks{&counted, false, {}, {}, {}, {}};

    // a failing setup call ends the run with its name and code
    auto setup_failed = [&](std::string_view call, long code) {
      mark_failed(result, t0, fmt::format("{}: {} returned {} ({})", method_, call, code, flag_name(code)));
      result.stats.cpu_seconds = thread_cpu_seconds() - start;
      return result;
    };

    SUNContext raw_context = nullptr;
    if (const int code = SUNContext_Create(nullptr, &raw_context); code != 0) return setup_failed("SUNContext_Create", code);
    ContextPtr context(raw_context);
    VectorPtr y(N_VNew_Serial(n, context.get()));
    Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(y.get()), n) = y0;
    CvodePtr mem(CVodeCreate(bdf_ ? CV_BDF : CV_ADAMS, context.get()));
    if (!mem) return setup_failed("CVodeCreate", CV_MEM_NULL);

    if (const int code = CVodeSetErrHandlerFn(mem.get(), cvode_error_handler, &callbacks)) return setup_failed("CVodeSetErrHandlerFn", code);
    if (const int code = CVodeInit(mem.get(), cvode_rhs, t0, y.get())) return setup_failed("CVodeInit", code);
    if (const int code = CVodeSetUserData(mem.get(), &callbacks)) return setup_failed("CVodeSetUserData", code);
    if (const int code = CVodeSStolerances(mem.get(), control_.rtol, control_.atol)) return setup_failed("CVodeSStolerances", code);
    if (const int code = CVodeSetMaxNumSteps(mem.get(), control_.max_steps)) return setup_failed("CVodeSetMaxNumSteps", code);
    if (const double max_step = max_adaptive_step(control_, system); std::isfinite(max_step)) {
      if (const int code = CVodeSetMaxStep(mem.get(), max_step)) return setup_failed("CVodeSetMaxStep", code);
    }

    // nonlinear and linear solvers: fixed point for Adams; Newton with dense LU or KLU for BDF
    NonlinSolPtr nonlinear;
    MatrixPtr matrix;
    LinSolPtr linear;
    if (!bdf_) {
      nonlinear.reset(SUNNonlinSol_FixedPoint(y.get(), 0, context.get()));
      if (const int code = CVodeSetNonlinearSolver(mem.get(), nonlinear.get())) return setup_failed("CVodeSetNonlinearSolver", code);
    } else if (system.has_sparse_jacobian()) {
      system.sparse_jacobian(t0, y0, callbacks.sparse_jac);
      with_diagonal(callbacks.sparse_jac);
      matrix.reset(SUNSparseMatrix(n, n, std::max<sunindextype>(1, callbacks.sparse_jac.nonZeros()), CSC_MAT, context.get()));
      linear.reset(SUNLinSol_KLU(y.get(), matrix.get(), context.get()));
      if (!linear) return setup_failed("SUNLinSol_KLU", CV_MEM_FAIL);
      if (const int code = CVodeSetLinearSolver(mem.get(), linear.get(), matrix.get())) return setup_failed("CVodeSetLinearSolver", code);
      if (const int code = CVodeSetJacFn(mem.get(), cvode_sparse_jacobian)) return setup_failed("CVodeSetJacFn", code);
    } else {
      matrix.reset(SUNDenseMatrix(n, n, context.get()));
      linear.reset(SUNLinSol_Dense(y.get(), matrix.get(), context.get()));
      if (const int code = CVodeSetLinearSolver(mem.get(), linear.get(), matrix.get())) return setup_failed("CVodeSetLinearSolver", code);
      if (system.has_jacobian()) {
        if (const int code = CVodeSetJacFn(mem.get(), cvode_dense_jacobian)) return setup_failed("CVodeSetJacFn", code);
      }
    }

    // projection after each step, where the system has one: CVODE supports it for BDF only
    if (Eigen::VectorXd probe = y0; bdf_ && system.project(probe)) {
      if (const int code = CVodeSetProjFn(mem.get(), cvode_projection)) return setup_failed("CVodeSetProjFn", code);
      if (const int code = CVodeSetProjErrEst(mem.get(), SUNFALSE)) return setup_failed("CVodeSetProjErrEst", code);
    }

    // events: CVODE's rootfinding with each event's direction; after a root, the handler and a re-initialisation
    const auto events = system.events();
    if (!events.empty()) {
      std::vector<int> directions;
      for (const auto& e : events) directions.push_back(e.direction);
      if (const int code = CVodeRootInit(mem.get(), static_cast<int>(events.size()), cvode_roots)) return setup_failed("CVodeRootInit", code);
      if (const int code = CVodeSetRootDirection(mem.get(), directions.data())) return setup_failed("CVodeSetRootDirection", code);
    }
    std::vector<int> roots_found(events.size());

    // CVODE's own counters for steps, rejections and linear algebra, summed over re-initialisations (which
    // reset them); f is counted in the wrapper
    auto add_counters = [&] {
      long steps = 0, error_fails = 0, convergence_fails = 0, setups = 0, iterations = 0, fd_jacobians = 0;
      CVodeGetNumSteps(mem.get(), &steps);
      CVodeGetNumErrTestFails(mem.get(), &error_fails);
      CVodeGetNumNonlinSolvConvFails(mem.get(), &convergence_fails);
      result.stats.steps += steps;
      result.stats.rejected += error_fails + convergence_fails;
      if (!bdf_) return;
      CVodeGetNumLinSolvSetups(mem.get(), &setups);
      CVodeGetNumNonlinSolvIters(mem.get(), &iterations);
      CVodeGetNumJacEvals(mem.get(), &fd_jacobians);
      // analytic Jacobians are counted in the callbacks; difference-quotient ones only by CVODE
      if (!system.has_jacobian() && !system.has_sparse_jacobian()) result.stats.jac_evals += fd_jacobians;
      result.stats.factorizations += setups;
      result.stats.linear_solves += iterations;
    };

    const double bound = divergence_bound(control_, y0);
    Eigen::Map<Eigen::VectorXd> ym(N_VGetArrayPointer(y.get()), n);
    double t = t0;
    for (const double target : t_out) {
      int code = CV_SUCCESS;
      while (true) {
        code = CVode(mem.get(), target, y.get(), &t, CV_NORMAL);
        if (code != CV_ROOT_RETURN) break;
        CVodeGetRootInfo(mem.get(), roots_found.data());
        const auto hit = std::find_if(roots_found.begin(), roots_found.end(), [](int r) { return r != 0; });
        Eigen::VectorXd y_event = ym;
        handle_event(result, events, static_cast<size_t>(hit - roots_found.begin()), t, y_event);
        ym = y_event;
        add_counters();
        if (const int re = CVodeReInit(mem.get(), t, y.get())) {
          code = re;
          break;
        }
        if (t >= target) break;
      }
      if (code < 0) {
        if (callbacks.non_finite || has_diverged(ym, bound)) mark_diverged(result, t);
        else mark_failed(result, t, fmt::format("{}: CVode returned {} ({}) at t = {:.9g}: {}", method_, code,
                                                flag_name(code), t, callbacks.last_error));
        break;
      }
      if (has_diverged(ym, bound)) {
        mark_diverged(result, t);
        break;
      }
      record_output(result, control_, t, ym);
    }
    add_counters();
    result.stats.cpu_seconds = thread_cpu_seconds() - start;
    return result;
  }

 private:
  std::string method_;
  bool bdf_;
  StepControl control_;
};

}  // namespace

void register_cvode_methods(MethodTable& table) {
  const auto cvode = [](bool bdf) {
    return [bdf](const Method& method, const StepControl& control) -> std::unique_ptr<Integrator> {
      return std::make_unique<CvodeIntegrator>(std::string(method.name), bdf, control);
    };
  };
  table.add({.name = "cvode-adams",
             .family = "cvode",
             .source = "SUNDIALS CVODE",
             .description = "adaptive, variable order Adams-Moulton, fixed-point iteration",
             .order = {1, 12, "1-12"},
             .stepping = Stepping::adaptive,
             .make = cvode(false)});
  table.add({.name = "cvode-bdf",
             .family = "cvode",
             .source = "SUNDIALS CVODE",
             .description = "adaptive, variable order BDF, Newton + dense LU or KLU",
             .order = {1, 5, "1-5"},
             .stepping = Stepping::adaptive,
             .dense = DenseMatrices::unless_sparse_jacobian,
             .make = cvode(true)});
}

}  // namespace stepwise
