// The CVODE and GSL adapters against the raw C APIs on the same problem (the pendulum, theta0 = 1,
// 10 s) at the same tolerance: the same RHS count is expected, and the ratio is the adapters' overhead.
#include "models/model.hpp"
#include "ratio_reporter.hpp"
#include "solvers/method_table.hpp"

#include <cvode/cvode.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <cmath>

namespace {

constexpr double rtol = 1e-8, atol = 1e-10, t_end = 10.0, w2 = 9.81;
long raw_rhs_calls = 0;

int cvode_rhs(sunrealtype, N_Vector y, N_Vector f, void*) {
  ++raw_rhs_calls;
  const double* yy = N_VGetArrayPointer(y);
  double* ff = N_VGetArrayPointer(f);
  ff[0] = yy[1];
  ff[1] = -w2 * std::sin(yy[0]);
  return 0;
}

int cvode_jac(sunrealtype, N_Vector y, N_Vector, SUNMatrix J, void*, N_Vector, N_Vector, N_Vector) {
  const double* yy = N_VGetArrayPointer(y);
  SM_ELEMENT_D(J, 0, 0) = 0;
  SM_ELEMENT_D(J, 0, 1) = 1;
  SM_ELEMENT_D(J, 1, 0) = -w2 * std::cos(yy[0]);
  SM_ELEMENT_D(J, 1, 1) = 0;
  return 0;
}

void BM_cvode_raw(benchmark::State& state) {
  for (auto _ : state) {
    raw_rhs_calls = 0;
    SUNContext ctx;
    SUNContext_Create(nullptr, &ctx);
    N_Vector y = N_VNew_Serial(2, ctx);
    N_VGetArrayPointer(y)[0] = 1.0;
    N_VGetArrayPointer(y)[1] = 0.0;
    void* mem = CVodeCreate(CV_BDF, ctx);
    CVodeInit(mem, cvode_rhs, 0.0, y);
    CVodeSStolerances(mem, rtol, atol);
    CVodeSetMaxNumSteps(mem, 100000);  // the default 500 stops this run short of t_end
    SUNMatrix A = SUNDenseMatrix(2, 2, ctx);
    SUNLinearSolver LS = SUNLinSol_Dense(y, A, ctx);
    CVodeSetLinearSolver(mem, LS, A);
    CVodeSetJacFn(mem, cvode_jac);
    double t = 0;
    if (CVode(mem, t_end, y, &t, CV_NORMAL) < 0) state.SkipWithError("CVode failed");
    benchmark::DoNotOptimize(N_VGetArrayPointer(y)[0]);
    CVodeFree(&mem);
    SUNLinSolFree(LS);
    SUNMatDestroy(A);
    N_VDestroy(y);
    SUNContext_Free(&ctx);
  }
  state.counters["rhs_evals"] = static_cast<double>(raw_rhs_calls);
}
BENCHMARK(BM_cvode_raw);

// the same problem through stepwise's Integrator interface
void run_adapter(benchmark::State& state, const char* method) {
  const auto model = stepwise::make_model("pendulum", {{"theta0", 1.0}});
  stepwise::StepControl control;
  control.rtol = rtol;
  control.atol = atol;
  const auto integrator = stepwise::make_integrator(method, control);
  long rhs = 0;
  for (auto _ : state) {
    const auto r = integrator->solve(*model, 0.0, model->initial_state(), std::vector{t_end});
    rhs = r.stats.rhs_evals;
    benchmark::DoNotOptimize(r.trajectory.y.back()[0]);
  }
  state.counters["rhs_evals"] = static_cast<double>(rhs);
}

void BM_cvode_adapter(benchmark::State& state) { run_adapter(state, "cvode-bdf"); }
BENCHMARK(BM_cvode_adapter);

int gsl_rhs(double, const double y[], double f[], void*) {
  ++raw_rhs_calls;
  f[0] = y[1];
  f[1] = -w2 * std::sin(y[0]);
  return GSL_SUCCESS;
}

void BM_gsl_raw(benchmark::State& state) {
  gsl_odeiv2_system sys{gsl_rhs, nullptr, 2, nullptr};
  for (auto _ : state) {
    raw_rhs_calls = 0;
    gsl_odeiv2_driver* d = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, 1e-3 * t_end, atol, rtol);
    double y[2] = {1.0, 0.0}, t = 0;
    if (gsl_odeiv2_driver_apply(d, &t, t_end, y) != GSL_SUCCESS) state.SkipWithError("gsl_odeiv2_driver_apply failed");
    benchmark::DoNotOptimize(y[0]);
    gsl_odeiv2_driver_free(d);
  }
  state.counters["rhs_evals"] = static_cast<double>(raw_rhs_calls);
}
BENCHMARK(BM_gsl_raw);

void BM_gsl_adapter(benchmark::State& state) { run_adapter(state, "gsl-rk8pd"); }
BENCHMARK(BM_gsl_adapter);

}  // namespace

int main(int argc, char** argv) {
  return stepwise::bench::run_with_ratios(argc, argv, {{"BM_cvode_adapter", "BM_cvode_raw"}, {"BM_gsl_adapter", "BM_gsl_raw"}});
}
