// arkode-erk-*, arkode-dirk-*, arkode-imex-*: SUNDIALS ARKODE (5.4, in SUNDIALS 6.4), its explicit, diagonally
// implicit and IMEX Runge-Kutta methods by their built-in Butcher tables, adaptive or at a fixed step, all
// through ARKStep (SUNDIALS' types stay in this file and sundials_support.*).
//
// - Explicit tables run in ARKStep with no implicit part, not in ERKStep: ERKStep 5.4 takes a table whose
//   last node is c_s = 1 for first-same-as-last even when its last row is not b, and reuses that stage as
//   the next step's first. Measured on the pendulum: Verner 6(5) converged at order 3 through ERKStep (7
//   calls of f a step for its 8 stages), at order 6 through ARKStep (test_arkode pins the order).
// - Every output time is a stop time (xxxSetStopTime): the step lands on it. ARKODE's interpolant is at most
//   of degree 5, so interpolated outputs would cap Verner 6(5) and Fehlberg 8(7) below their order.
// - DIRK: f all implicit, Newton with dense LU (analytic or difference-quotient Jacobian) or KLU on the
//   system's sparse Jacobian. IMEX: the model's split (capabilities/imex_split.hpp), its stiff part
//   implicit with KLU on df_I/dy or, where the model solves (1 - gamma df_I/dy) x = b itself (the fluid's
//   viscosity, by FFT), with that solve as a matrix-embedded linear solver; the rest explicit; a call of either
//   part counts as one call of f.
// - Events use ARKODE's rootfinding, as CVODE's do (sundials::output_loop).
#include "solvers/method.hpp"

#include "solvers/sundials_support.hpp"

#include <arkode/arkode_arkstep.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>


namespace stepwise {
namespace {

using namespace sundials;

enum class Kind { erk, dirk, imex };

// one registered ARKODE method: its name, ARKODE's table(s), and what the table is
struct Table {
  std::string_view name;
  Kind kind;
  ARKODE_ERKTableID erk;    // the explicit table (ERK, IMEX), else ARKODE_ERK_NONE
  ARKODE_DIRKTableID dirk;  // the implicit table (DIRK, IMEX), else ARKODE_DIRK_NONE
  int order;                // the method's order (the embedding's is one less)
  std::string_view description;
};

constexpr Table tables[] = {
    {"arkode-erk-heun-euler21", Kind::erk, ARKODE_HEUN_EULER_2_1_2, ARKODE_DIRK_NONE, 2, "explicit Heun-Euler 2(1)"},
    {"arkode-erk-bogacki-shampine32", Kind::erk, ARKODE_BOGACKI_SHAMPINE_4_2_3, ARKODE_DIRK_NONE, 3, "explicit Bogacki-Shampine 3(2)"},
    {"arkode-erk-zonneveld43", Kind::erk, ARKODE_ZONNEVELD_5_3_4, ARKODE_DIRK_NONE, 4, "explicit Zonneveld 4(3)"},
    {"arkode-erk-cash-karp54", Kind::erk, ARKODE_CASH_KARP_6_4_5, ARKODE_DIRK_NONE, 5, "explicit Cash-Karp 5(4)"},
    {"arkode-erk-fehlberg54", Kind::erk, ARKODE_FEHLBERG_6_4_5, ARKODE_DIRK_NONE, 5, "explicit Fehlberg 5(4)"},
    {"arkode-erk-dormand-prince54", Kind::erk, ARKODE_DORMAND_PRINCE_7_4_5, ARKODE_DIRK_NONE, 5, "explicit Dormand-Prince 5(4)"},
    {"arkode-erk-verner65", Kind::erk, ARKODE_VERNER_8_5_6, ARKODE_DIRK_NONE, 6, "explicit Verner 6(5)"},
    {"arkode-erk-fehlberg87", Kind::erk, ARKODE_FEHLBERG_13_7_8, ARKODE_DIRK_NONE, 8, "explicit Fehlberg 8(7)"},
    {"arkode-dirk-sdirk21", Kind::dirk, ARKODE_ERK_NONE, ARKODE_SDIRK_2_1_2, 2, "SDIRK 2(1), Newton"},
    {"arkode-dirk-trbdf2", Kind::dirk, ARKODE_ERK_NONE, ARKODE_TRBDF2_3_3_2, 2, "TR-BDF2 2(3), Newton"},
    {"arkode-dirk-kvaerno32", Kind::dirk, ARKODE_ERK_NONE, ARKODE_KVAERNO_4_2_3, 3, "Kvaerno 3(2) ESDIRK, Newton"},
    {"arkode-dirk-kvaerno43", Kind::dirk, ARKODE_ERK_NONE, ARKODE_KVAERNO_5_3_4, 4, "Kvaerno 4(3) ESDIRK, Newton"},
    {"arkode-dirk-kvaerno54", Kind::dirk, ARKODE_ERK_NONE, ARKODE_KVAERNO_7_4_5, 5, "Kvaerno 5(4) ESDIRK (7 stages), Newton"},
    {"arkode-imex-ark324", Kind::imex, ARKODE_ARK324L2SA_ERK_4_2_3, ARKODE_ARK324L2SA_DIRK_4_2_3, 3, "IMEX ARK 3(2)4L[2]SA on the model's stiff/non-stiff split"},
    {"arkode-imex-ark436", Kind::imex, ARKODE_ARK436L2SA_ERK_6_3_4, ARKODE_ARK436L2SA_DIRK_6_3_4, 4, "IMEX ARK 4(3)6L[2]SA on the model's stiff/non-stiff split"},
    {"arkode-imex-ark548", Kind::imex, ARKODE_ARK548L2SA_ERK_8_4_5, ARKODE_ARK548L2SA_DIRK_8_4_5, 5, "IMEX ARK 5(4)8L[2]SA on the model's stiff/non-stiff split"},
};

// the Newton iterations' tolerances and their number at a fixed step (see solve())
constexpr double fixed_newton_rtol = 1e-10, fixed_newton_atol = 1e-12;
constexpr int fixed_newton_iterations = 10;


// An IMEX run's Newton systems (1 - gamma df_I/dy) x = b solved by the model's own direct solve
// (ImexSplit::implicit_solve): a SUNDIALS "matrix-embedded" linear solver, gamma read from ARKStep at each solve
struct EmbeddedSolve {
  void* arkode = nullptr;
  const ImexSplit* split = nullptr;
};

SUNLinearSolver embedded_solver(EmbeddedSolve* content, SUNContext context) {
  SUNLinearSolver s = SUNLinSolNewEmpty(context);
  if (!s) return nullptr;
  s->content = content;
  s->ops->gettype = [](SUNLinearSolver) { return SUNLINEARSOLVER_MATRIX_EMBEDDED; };
  s->ops->solve = [](SUNLinearSolver self, SUNMatrix, N_Vector x, N_Vector b, sunrealtype) {
    const auto* e = static_cast<const EmbeddedSolve*>(self->content);
    sunrealtype gamma = 0;
    if (ARKStepGetCurrentGamma(e->arkode, &gamma) != ARK_SUCCESS) return static_cast<int>(SUNLS_MEM_NULL);
    N_VScale(1.0, b, x);
    Eigen::Map<Eigen::VectorXd> v(N_VGetArrayPointer(x), N_VGetLength(x));
    e->split->implicit_solve(gamma, v);
    return static_cast<int>(SUNLS_SUCCESS);
  };
  s->ops->free = [](SUNLinearSolver self) {
    self->content = nullptr;  // not SUNDIALS' to free
    SUNLinSolFreeEmpty(self);
    return static_cast<int>(SUNLS_SUCCESS);
  };
  return s;
}

std::string arkode_flag_name(long flag) { return return_flag_name(ARKStepGetReturnFlagName, flag); }

class ArkodeIntegrator final : public Integrator {
 public:
  ArkodeIntegrator(const Method& method, const Table& table, StepControl control) : method_(method), table_(table), control_(control) {}

  RunResult solve(const OdeSystem& system, double t0, const Eigen::VectorXd& y0, std::span<const double> t_out) const override {
    if (!method_.needs.offered_by(system)) throw BadMethod(method_requirement(method_, system));
    RunResult result = begin_run(t0, y0);
    CountedSystem counted(system, result.stats);
    Callbacks callbacks;
    callbacks.system = &counted;
    if (table_.kind == Kind::imex) callbacks.split = system.as<ImexSplit>();
    const int n = system.size();
    const std::string_view name = method_.name;
    auto setup_failed = [&](std::string_view call, long code) {
      mark_failed(result, t0, fmt::format("{}: {} returned {} ({})", name, call, code, arkode_flag_name(code)));
      return result;
    };

    ContextPtr context;
    VectorPtr y;
    if (const int code = serial_state(y0, context, y)) return setup_failed("SUNContext_Create", code);
    const double max_step = max_adaptive_step(control_, system);
    const auto events = events_of(system);
    std::vector<int> directions;
    for (const auto& e : events) directions.push_back(e.direction);

    const bool imex = table_.kind == Kind::imex, implicit = table_.kind != Kind::erk;
    ARKRhsFn fe = imex ? sundials::explicit_part : implicit ? nullptr : sundials::rhs;
    ARKRhsFn fi = imex ? sundials::implicit_part : implicit ? sundials::rhs : nullptr;
    ArkodePtr mem(ARKStepCreate(fe, fi, t0, y.get(), context.get()));
    if (!mem) return setup_failed("ARKStepCreate", ARK_MEM_NULL);
    void* m = mem.get();
    if (const int code = ARKStepSetErrHandlerFn(m, error_handler, &callbacks)) return setup_failed("ARKStepSetErrHandlerFn", code);
    if (const int code = ARKStepSetUserData(m, &callbacks)) return setup_failed("ARKStepSetUserData", code);
    if (const int code = ARKStepSetTableNum(m, table_.dirk, table_.erk)) return setup_failed("ARKStepSetTableNum", code);
    if (control_.dt) {
      if (const int code = ARKStepSetFixedStep(m, *control_.dt)) return setup_failed("ARKStepSetFixedStep", code);
    }
    // at a fixed step the tolerances only end the Newton iterations: tight, with room for the iterations to
    // get there, so that a fixed-step run's error is the method's (ARKODE's defaults, rtol 1e-4 and 3
    // iterations, left Kvaerno 4(3) converging at order 1.1 on the pendulum)
    if (const int code = control_.dt ? ARKStepSStolerances(m, fixed_newton_rtol, fixed_newton_atol) : ARKStepSStolerances(m, control_.rtol, control_.atol)) {
      return setup_failed("ARKStepSStolerances", code);
    }
    if (control_.dt && implicit) {
      if (const int code = ARKStepSetMaxNonlinIters(m, fixed_newton_iterations)) return setup_failed("ARKStepSetMaxNonlinIters", code);
    }
    if (const int code = ARKStepSetMaxNumSteps(m, control_.max_steps)) return setup_failed("ARKStepSetMaxNumSteps", code);
    if (std::isfinite(max_step) && !control_.dt) {
      if (const int code = ARKStepSetMaxStep(m, max_step)) return setup_failed("ARKStepSetMaxStep", code);
    }

    // Newton's linear systems: the model's own solve (IMEX, where it has one), KLU on the sparse pattern
    // (df_I/dy for IMEX), else dense LU
    MatrixPtr matrix;
    EmbeddedSolve embedded{m, callbacks.split};
    LinSolPtr linear;
    if (imex && callbacks.split->implicit_solve) {
      linear.reset(embedded_solver(&embedded, context.get()));
      if (!linear) return setup_failed("SUNLinSolNewEmpty", ARK_MEM_FAIL);
      if (const int code = ARKStepSetLinearSolver(m, linear.get(), nullptr)) return setup_failed("ARKStepSetLinearSolver", code);
    } else if (implicit && (imex || system.as<SparseJacobian>())) {
      initial_pattern(callbacks, t0, y0);
      matrix.reset(sparse_matrix(callbacks, context.get()));
      const char* made_by = nullptr;
      linear.reset(sparse_solver(y.get(), matrix.get(), context.get(), made_by));
      if (!linear) return setup_failed(made_by, ARK_MEM_FAIL);
      if (const int code = ARKStepSetLinearSolver(m, linear.get(), matrix.get())) return setup_failed("ARKStepSetLinearSolver", code);
      if (const int code = ARKStepSetJacFn(m, sundials::sparse_jacobian)) return setup_failed("ARKStepSetJacFn", code);
    } else if (implicit) {
      matrix.reset(SUNDenseMatrix(n, n, context.get()));
      linear.reset(SUNLinSol_Dense(y.get(), matrix.get(), context.get()));
      if (const int code = ARKStepSetLinearSolver(m, linear.get(), matrix.get())) return setup_failed("ARKStepSetLinearSolver", code);
      if (system.as<DenseJacobian>()) {
        if (const int code = ARKStepSetJacFn(m, sundials::dense_jacobian)) return setup_failed("ARKStepSetJacFn", code);
      }
    }
    if (imex && callbacks.split->linear) {
      if (const int code = ARKStepSetLinear(m, 0)) return setup_failed("ARKStepSetLinear", code);
    }
    if (!events.empty()) {
      if (const int code = ARKStepRootInit(m, static_cast<int>(events.size()), sundials::roots)) return setup_failed("ARKStepRootInit", code);
      if (const int code = ARKStepSetRootDirection(m, directions.data())) return setup_failed("ARKStepSetRootDirection", code);
    }
    const auto add_counters = [&] {
      long steps = 0, error_fails = 0, convergence_fails = 0, setups = 0, iterations = 0, jacobians = 0;
      ARKStepGetNumSteps(m, &steps);
      ARKStepGetNumErrTestFails(m, &error_fails);
      ARKStepGetNumNonlinSolvConvFails(m, &convergence_fails);
      ARKStepGetNumLinSolvSetups(m, &setups);
      ARKStepGetNumNonlinSolvIters(m, &iterations);
      ARKStepGetNumJacEvals(m, &jacobians);
      result.stats.steps += steps;
      result.stats.rejected += error_fails + convergence_fails;
      result.stats.factorizations += setups;
      result.stats.linear_solves += iterations;
      // analytic Jacobians are counted in the callbacks; difference-quotient ones only by ARKODE
      if (implicit && !imex && !system.as<DenseJacobian>() && !system.as<SparseJacobian>()) result.stats.jac_evals += jacobians;
    };
    const Driver driver{
        .method = name,
        .evolve_call = "ARKStepEvolve",
        .root_return = ARK_ROOT_RETURN,
        .evolve = [&](double target, N_Vector v, double& t, bool one_step) {
          if (const int code = ARKStepSetStopTime(m, target)) return code;
          return ARKStepEvolve(m, target, v, &t, one_step ? ARK_ONE_STEP : ARK_NORMAL);
        },
        .root_info = [&](int* found) { ARKStepGetRootInfo(m, found); },
        .reinit = [&](double t, N_Vector v) { return ARKStepReInit(m, fe, fi, t, v); },
        .state_at = [&](double t, N_Vector v) { return ARKStepGetDky(m, t, 0, v); },
        .add_counters = add_counters,
        .flag_name = arkode_flag_name,
    };
    output_loop(driver, callbacks, y.get(), t0, t_out, control_, result);
    return result;
  }

 private:
  const Method& method_;
  const Table& table_;
  StepControl control_;
};

}  // namespace

std::optional<sundials::ArkodeTables> sundials::arkode_tables(std::string_view method) {
  for (const Table& t : tables)
    if (t.name == method) return ArkodeTables{t.erk, t.dirk};
  return std::nullopt;
}

void register_arkode_methods(MethodTable& table) {
  for (const Table& t : tables) {
    table.add({
        .name = t.name,
        .family = Family::arkode,
        .source = Source::arkode,
        .description = t.description,
        // the order text outlives the table: one static string per order
        .order = {t.order, t.order, std::array<std::string_view, 9>{"0", "1", "2", "3", "4", "5", "6", "7", "8"}[static_cast<size_t>(t.order)]},
        .stepping = Stepping::fixed_or_adaptive,
        .needs = t.kind == Kind::imex ? needs_imex_split : Requirement{},
        .dense = t.kind == Kind::dirk ? DenseMatrices::unless_sparse_jacobian : DenseMatrices::none,
        .on_ranks = OnRanks::arkode,
        .make = [&t](const Method& method, const StepControl& control) -> std::unique_ptr<Integrator> {
          return std::make_unique<ArkodeIntegrator>(method, t, control);
        },
    });
  }
}

}  // namespace stepwise
