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

#include "solvers/sundials_support.hpp"

#include <cvode/cvode.h>
#include <cvode/cvode_proj.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>

namespace stepwise {
namespace {

using namespace sundials;

std::string cvode_flag_name(long flag) { return return_flag_name(CVodeGetReturnFlagName, flag); }

// CVODE's projection: corr takes ycur onto the system's manifold (the error estimate is not projected)
int cvode_projection(sunrealtype, N_Vector ycur, N_Vector corr, sunrealtype, N_Vector, void* user_data) {
  auto& c = *static_cast<Callbacks*>(user_data);
  const auto n = static_cast<Eigen::Index>(N_VGetLength(ycur));
  const Eigen::Map<const Eigen::VectorXd> y(N_VGetArrayPointer(ycur), n);
  c.projected = y;
  c.system->as<Projection>()->project(c.projected);
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(corr), n) = c.projected - y;
  return 0;
}

class CvodeIntegrator final : public Integrator {
 public:
  CvodeIntegrator(std::string method, bool bdf, StepControl control)
      : method_(std::move(method)), bdf_(bdf), control_(control) {}

  RunResult solve(const OdeSystem& system, double t0, const Eigen::VectorXd& y0,
                      std::span<const double> t_out) const override {
    RunResult result = begin_run(t0, y0);
    CountedSystem counted(system, result.stats);
    const int n = system.size();
    Callbacks callbacks;
    callbacks.system = &counted;

    // a failing setup call ends the run with its name and code
    auto setup_failed = [&](std::string_view call, long code) {
      mark_failed(result, t0, fmt::format("{}: {} returned {} ({})", method_, call, code, cvode_flag_name(code)));
      return result;
    };

    ContextPtr context;
    VectorPtr y;
    if (const int code = serial_state(y0, context, y)) return setup_failed("SUNContext_Create", code);
    CvodePtr mem(CVodeCreate(bdf_ ? CV_BDF : CV_ADAMS, context.get()));
    if (!mem) return setup_failed("CVodeCreate", CV_MEM_NULL);

    if (const int code = CVodeSetErrHandlerFn(mem.get(), error_handler, &callbacks)) return setup_failed("CVodeSetErrHandlerFn", code);
    if (const int code = CVodeInit(mem.get(), sundials::rhs, t0, y.get())) return setup_failed("CVodeInit", code);
    if (const int code = CVodeSetUserData(mem.get(), &callbacks)) return setup_failed("CVodeSetUserData", code);
    if (const int code = CVodeSStolerances(mem.get(), control_.rtol, control_.atol)) return setup_failed("CVodeSStolerances", code);
    if (const int code = CVodeSetMaxNumSteps(mem.get(), control_.max_steps)) return setup_failed("CVodeSetMaxNumSteps", code);
    if (const double max_step = max_adaptive_step(control_, system); std::isfinite(max_step)) {
      if (const int code = CVodeSetMaxStep(mem.get(), max_step)) return setup_failed("CVodeSetMaxStep", code);
    }

    // nonlinear and linear solvers: fixed point for Adams; Newton with dense LU, or KLU or UMFPACK (sparse_solver) for BDF
    NonlinSolPtr nonlinear;
    MatrixPtr matrix;
    LinSolPtr linear;
    if (!bdf_) {
      nonlinear.reset(SUNNonlinSol_FixedPoint(y.get(), 0, context.get()));
      if (const int code = CVodeSetNonlinearSolver(mem.get(), nonlinear.get())) return setup_failed("CVodeSetNonlinearSolver", code);
    } else if (system.as<SparseJacobian>()) {
      initial_pattern(callbacks, t0, y0);
      matrix.reset(sparse_matrix(callbacks, context.get()));
      const char* made_by = nullptr;
      linear.reset(sparse_solver(y.get(), matrix.get(), context.get(), made_by));
      if (!linear) return setup_failed(made_by, CV_MEM_FAIL);
      if (const int code = CVodeSetLinearSolver(mem.get(), linear.get(), matrix.get())) return setup_failed("CVodeSetLinearSolver", code);
      if (const int code = CVodeSetJacFn(mem.get(), sundials::sparse_jacobian)) return setup_failed("CVodeSetJacFn", code);
    } else {
      matrix.reset(SUNDenseMatrix(n, n, context.get()));
      linear.reset(SUNLinSol_Dense(y.get(), matrix.get(), context.get()));
      if (const int code = CVodeSetLinearSolver(mem.get(), linear.get(), matrix.get())) return setup_failed("CVodeSetLinearSolver", code);
      if (system.as<DenseJacobian>()) {
        if (const int code = CVodeSetJacFn(mem.get(), sundials::dense_jacobian)) return setup_failed("CVodeSetJacFn", code);
      }
    }

    // projection after each step, where the system has one: CVODE supports it for BDF only
    if (bdf_ && system.as<Projection>()) {
      if (const int code = CVodeSetProjFn(mem.get(), cvode_projection)) return setup_failed("CVodeSetProjFn", code);
      if (const int code = CVodeSetProjErrEst(mem.get(), SUNFALSE)) return setup_failed("CVodeSetProjErrEst", code);
    }

    // events: CVODE's rootfinding with each event's direction; after a root, the handler and a re-initialisation
    const auto events = events_of(system);
    if (!events.empty()) {
      std::vector<int> directions;
      for (const auto& e : events) directions.push_back(e.direction);
      if (const int code = CVodeRootInit(mem.get(), static_cast<int>(events.size()), sundials::roots)) return setup_failed("CVodeRootInit", code);
      if (const int code = CVodeSetRootDirection(mem.get(), directions.data())) return setup_failed("CVodeSetRootDirection", code);
    }

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
      if (!system.as<DenseJacobian>() && !system.as<SparseJacobian>()) result.stats.jac_evals += fd_jacobians;
      result.stats.factorizations += setups;
      result.stats.linear_solves += iterations;
    };

    const Driver driver{
        .method = method_,
        .evolve_call = "CVode",
        .root_return = CV_ROOT_RETURN,
        .evolve = [&](double target, N_Vector v, double& t, bool one_step) {
          if (!one_step) return CVode(mem.get(), target, v, &t, CV_NORMAL);
          if (const int code = CVodeSetStopTime(mem.get(), target)) return code;
          return CVode(mem.get(), target, v, &t, CV_ONE_STEP);
        },
        .root_info = [&](int* found) { CVodeGetRootInfo(mem.get(), found); },
        .reinit = [&](double t, N_Vector v) { return CVodeReInit(mem.get(), t, v); },
        .state_at = [&](double t, N_Vector v) { return CVodeGetDky(mem.get(), t, 0, v); },
        .add_counters = add_counters,
        .flag_name = cvode_flag_name,
    };
    output_loop(driver, callbacks, y.get(), t0, t_out, control_, result);
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
             .family = Family::cvode,
             .source = Source::cvode,
             .description = "adaptive, variable order Adams-Moulton, fixed-point iteration",
             .order = {1, 12, "1-12"},
             .stepping = Stepping::adaptive,
             .on_ranks = OnRanks::cvode_adams,
             .make = cvode(false)});
  table.add({.name = "cvode-bdf",
             .family = Family::cvode,
             .source = Source::cvode,
             .description = "adaptive, variable order BDF, Newton + dense LU or KLU",
             .order = {1, 5, "1-5"},
             .stepping = Stepping::adaptive,
             .dense = DenseMatrices::unless_sparse_jacobian,
             .on_ranks = OnRanks::cvode_bdf,
             .make = cvode(true)});
}

}  // namespace stepwise
