// ida: SUNDIALS IDA (6.4), the variable-order BDF solver of differential-algebraic systems, on particles held by
// distance constraints (the DistanceConstraints capability) written as a DAE rather than an ODE. With x, v the
// coordinates and velocities, a the external acceleration, W the inverse masses, G(x) the constraints' gradients
// (a row n_j at a, -n_j at b) and lambda, mu a multiplier a constraint, the stabilised index-2 form of Gear,
// Gupta & Leimkuhler (1985):
//   x' = v + W G^T mu,   v' = a + W G^T lambda,   g_j(x) + alpha_j lambda_j = 0,   G v = 0 (mu_j = 0 where alpha_j > 0)
// (a compliant constraint, alpha > 0, is a spring: its lambda = -g/alpha, an index-1 equation). mu is 0 along the
// exact solution; it keeps the positions on g = 0 while the velocities keep G v = 0, so neither drifts beyond
// IDA's tolerance. SUNDIALS' types stay in this file.
//
// Pitfalls handled here:
// - IDACalcIC computes consistent initial values of index-1 systems only: for g(x) = 0 its matrix (d/d lambda,
//   d/d mu, d/dx', d/dv') is singular. The initial values are made here instead: x, v from the scene (on the
//   constraints), x' = v, v' the model's own constrained acceleration (its f), lambda from G W G^T lambda =
//   G (v' - a) (Eigen's LDLT, the constraints' normal equations), mu = 0;
// - the multipliers of an index-2 system must not enter IDA's error test (IDASetId, IDASetSuppressAlg), or the
//   step size collapses;
// - IDA's counters are read once at the end (no events: the constrained scenes have none), f (the external
//   acceleration) is counted in the residual.
#include "solvers/method.hpp"

#include "solvers/capabilities/distance_constraints.hpp"
#include "solvers/sundials_support.hpp"

#include <ida/ida.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Cholesky>


namespace stepwise {
namespace {

using namespace sundials;

constexpr double multiplier_atol = 1.0;  // see IDASVtolerances below

struct IdaFree { void operator()(void* mem) const { IDAFree(&mem); } };
using IdaPtr = std::unique_ptr<void, IdaFree>;

std::string ida_flag_name(long flag) { return return_flag_name(IDAGetReturnFlagName, flag); }

// the DAE's pieces, reached through IDA's user_data: the unknowns laid out as (x, v, lambda, mu)
struct Dae {
  const CountedSystem* system;
  const DistanceConstraints* c;
  Eigen::Index n;  // coordinates
  Eigen::Index m;  // constraints
  mutable Eigen::VectorXd a;  // the external acceleration's scratch
  bool* non_finite;

  // out += W G^T s (s a value per constraint), on the coordinates
  void add_forces(const double* x, const double* s, double* out) const {
    const int d = c->dimension;
    double dir[3];
    for (Eigen::Index j = 0; j < m; ++j) {
      const DistanceConstraint& k = c->constraints[static_cast<size_t>(j)];
      c->violation(k, x, dir);
      const double wa = c->inverse_mass[static_cast<size_t>(k.a)], wb = k.b < 0 ? 0.0 : c->inverse_mass[static_cast<size_t>(k.b)];
      for (int i = 0; i < d; ++i) {
        out[k.a * d + i] += wa * dir[i] * s[j];
        if (k.b >= 0) out[k.b * d + i] -= wb * dir[i] * s[j];
      }
    }
  }

  // G, dense (m x n)
  Eigen::MatrixXd gradients(const double* x) const {
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(m, n);
    const int d = c->dimension;
    double dir[3];
    for (Eigen::Index j = 0; j < m; ++j) {
      const DistanceConstraint& k = c->constraints[static_cast<size_t>(j)];
      c->violation(k, x, dir);
      for (int i = 0; i < d; ++i) {
        G(j, k.a * d + i) = dir[i];
        if (k.b >= 0) G(j, k.b * d + i) = -dir[i];
      }
    }
    return G;
  }

  bool moving(Eigen::Index coordinate) const { return c->inverse_mass[static_cast<size_t>(coordinate / c->dimension)] > 0; }
};

int residual(sunrealtype t, N_Vector yy, N_Vector yp, N_Vector rr, void* user_data) {
  const Dae& dae = *static_cast<const Dae*>(user_data);
  const double* y = N_VGetArrayPointer(yy);
  const double* dy = N_VGetArrayPointer(yp);
  double* r = N_VGetArrayPointer(rr);
  const Eigen::Index n = dae.n, m = dae.m;
  const double *x = y, *v = y + n, *lambda = y + 2 * n, *mu = y + 2 * n + m;
  dae.c->external(t, x, v, dae.a.data());
  ++dae.system->stats().rhs_evals;
  double* rx = r;
  double* rv = r + n;
  for (Eigen::Index i = 0; i < n; ++i) {
    rx[i] = 0;
    rv[i] = dae.moving(i) ? dae.a[i] : 0.0;
  }
  dae.add_forces(x, mu, rx);
  dae.add_forces(x, lambda, rv);
  for (Eigen::Index i = 0; i < n; ++i) {
    rx[i] = dy[i] - v[i] - rx[i];
    rv[i] = dy[n + i] - rv[i];
  }
  const int d = dae.c->dimension;
  double dir[3];
  for (Eigen::Index j = 0; j < m; ++j) {
    const DistanceConstraint& k = dae.c->constraints[static_cast<size_t>(j)];
    const double g = dae.c->violation(k, x, dir);
    r[2 * n + j] = g + k.compliance * lambda[j];
    double rate = 0;  // G v: the constraint's rate of change
    for (int i = 0; i < d; ++i) rate += dir[i] * (v[k.a * d + i] - (k.b < 0 ? 0.0 : v[k.b * d + i]));
    r[2 * n + m + j] = k.compliance > 0 ? mu[j] : rate;
  }
  for (Eigen::Index i = 0; i < 2 * (n + m); ++i)
    if (!std::isfinite(r[i])) {
      *dae.non_finite = true;
      return 1;  // recoverable: IDA cuts the step
    }
  return 0;
}

class IdaIntegrator final : public Integrator {
 public:
  explicit IdaIntegrator(StepControl control) : control_(std::move(control)) {}

  RunResult solve(const OdeSystem& system, double t0, const Eigen::VectorXd& y0, std::span<const double> t_out) const override {
    RunResult result = begin_run(t0, y0);
    CountedSystem counted(system, result.stats);
    const auto* constraints = counted.as<DistanceConstraints>();
    Callbacks callbacks;
    callbacks.system = &counted;
    Dae dae{&counted, constraints, system.size() / 2, static_cast<Eigen::Index>(constraints->constraints.size()), Eigen::VectorXd(system.size() / 2),
            &callbacks.non_finite};
    const Eigen::Index n = dae.n, m = dae.m, size = 2 * (n + m);

    auto setup_failed = [&](std::string_view call, long code) {
      mark_failed(result, t0, fmt::format("ida: {} returned {} ({})", call, code, ida_flag_name(code)));
      return result;
    };

    // consistent initial values (see the top of the file)
    Eigen::VectorXd Y = Eigen::VectorXd::Zero(size), dY = Eigen::VectorXd::Zero(size);
    Y.head(2 * n) = y0;
    Eigen::VectorXd f(system.size());
    counted.rhs(t0, y0, f);
    dY.head(2 * n) = f;
    constraints->external(t0, y0.data(), y0.data() + n, dae.a.data());
    Eigen::VectorXd pull = f.tail(n);
    for (Eigen::Index i = 0; i < n; ++i) pull[i] -= dae.moving(i) ? dae.a[i] : 0.0;
    const Eigen::MatrixXd G = dae.gradients(y0.data());
    Eigen::VectorXd w(n);
    for (Eigen::Index i = 0; i < n; ++i) w[i] = constraints->inverse_mass[static_cast<size_t>(i / constraints->dimension)];
    Y.segment(2 * n, m) = (G * w.asDiagonal() * G.transpose()).ldlt().solve(G * pull);

    ContextPtr context;
    VectorPtr yy, yp, id;
    if (const int code = serial_state(Y, context, yy)) return setup_failed("SUNContext_Create", code);
    yp.reset(N_VNew_Serial(size, context.get()));
    id.reset(N_VNew_Serial(size, context.get()));
    Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(yp.get()), size) = dY;
    Eigen::Map<Eigen::VectorXd> ids(N_VGetArrayPointer(id.get()), size);
    ids.head(2 * n).setOnes();
    ids.tail(2 * m).setZero();

    IdaPtr mem(IDACreate(context.get()));
    if (!mem) return setup_failed("IDACreate", IDA_MEM_NULL);
    if (const int code = IDASetErrHandlerFn(mem.get(), error_handler, &callbacks)) return setup_failed("IDASetErrHandlerFn", code);
    if (const int code = IDAInit(mem.get(), residual, t0, yy.get(), yp.get())) return setup_failed("IDAInit", code);
    if (const int code = IDASetUserData(mem.get(), &dae)) return setup_failed("IDASetUserData", code);
    // the multipliers' absolute tolerance loose: they are out of the error test, and Newton's convergence test
    // on them at the state's atol fails at tight tolerances (an index-2 iteration matrix's condition grows as
    // 1/h^2, and the chain's multipliers start at 0: at rtol 1e-9, IDA_CONV_FAIL at t = 0)
    VectorPtr atol(N_VNew_Serial(size, context.get()));
    Eigen::Map<Eigen::VectorXd> atols(N_VGetArrayPointer(atol.get()), size);
    atols.head(2 * n).setConstant(control_.atol);
    atols.tail(2 * m).setConstant(multiplier_atol);
    if (const int code = IDASVtolerances(mem.get(), control_.rtol, atol.get())) return setup_failed("IDASVtolerances", code);
    if (const int code = IDASetId(mem.get(), id.get())) return setup_failed("IDASetId", code);
    if (const int code = IDASetSuppressAlg(mem.get(), SUNTRUE)) return setup_failed("IDASetSuppressAlg", code);
    if (const int code = IDASetMaxNumSteps(mem.get(), control_.max_steps)) return setup_failed("IDASetMaxNumSteps", code);
    if (const double max_step = max_adaptive_step(control_, system); std::isfinite(max_step)) {
      if (const int code = IDASetMaxStep(mem.get(), max_step)) return setup_failed("IDASetMaxStep", code);
    }
    MatrixPtr matrix(SUNDenseMatrix(size, size, context.get()));
    LinSolPtr linear(SUNLinSol_Dense(yy.get(), matrix.get(), context.get()));
    if (const int code = IDASetLinearSolver(mem.get(), linear.get(), matrix.get())) return setup_failed("IDASetLinearSolver", code);

    auto add_counters = [&] {
      long steps = 0, error_fails = 0, convergence_fails = 0, setups = 0, iterations = 0, jacobians = 0;
      IDAGetNumSteps(mem.get(), &steps);
      IDAGetNumErrTestFails(mem.get(), &error_fails);
      IDAGetNumNonlinSolvConvFails(mem.get(), &convergence_fails);
      IDAGetNumLinSolvSetups(mem.get(), &setups);
      IDAGetNumNonlinSolvIters(mem.get(), &iterations);
      IDAGetNumJacEvals(mem.get(), &jacobians);
      result.stats.steps += steps;
      result.stats.rejected += error_fails + convergence_fails;
      result.stats.jac_evals += jacobians;  // difference quotients of the residual
      result.stats.factorizations += setups;
      result.stats.linear_solves += iterations;
    };
    const Driver driver{
        .method = "ida",
        .evolve_call = "IDASolve",
        .root_return = IDA_ROOT_RETURN,
        .evolve = [&](double target, N_Vector v, double& t, bool one_step) {
          if (!one_step) return IDASolve(mem.get(), target, &t, v, yp.get(), IDA_NORMAL);
          if (const int code = IDASetStopTime(mem.get(), target)) return code;
          return IDASolve(mem.get(), target, &t, v, yp.get(), IDA_ONE_STEP);
        },
        .root_info = [&](int* found) { IDAGetRootInfo(mem.get(), found); },
        .reinit = [&](double t, N_Vector v) { return IDAReInit(mem.get(), t, v, yp.get()); },
        .state_at = [&](double t, N_Vector v) {
          const int code = IDAGetDky(mem.get(), t, 0, v);
          return code != 0 ? code : IDAGetDky(mem.get(), t, 1, yp.get());
        },
        .add_counters = add_counters,
        .flag_name = ida_flag_name,
    };
    output_loop(driver, callbacks, yy.get(), t0, t_out, control_, result);
    return result;
  }

 private:
  StepControl control_;
};

}  // namespace

void register_ida_methods(MethodTable& table) {
  table.add({.name = "ida",
             .family = Family::constrained,
             .source = Source::ida,
             .description = "adaptive, variable order BDF on the constrained scene as a DAE (stabilised index 2), Newton + dense LU; constrained scenes only",
             .order = {1, 5, "1-5"},
             .stepping = Stepping::adaptive,
             .needs = needs_distance_constraints,
             .dense = DenseMatrices::constrained_dae,
             .make = [](const Method&, const StepControl& control) -> std::unique_ptr<Integrator> { return std::make_unique<IdaIntegrator>(control); }});
}

}  // namespace stepwise
