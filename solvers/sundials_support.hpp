// What the SUNDIALS adapters (methods/cvode.cpp, methods/arkode.cpp, methods/ida.cpp) share: RAII handles, the C
// callbacks that reach the counted system, the loop over output times with events, and the sparse direct solver
// (sunlinsol_umfpack.cpp). SUNDIALS' types appear only here, in those three files and in distributed_lines.cpp
// (the same methods on the parallel vector).
#pragma once

#include <stepwise/solvers/capabilities/imex_split.hpp>
#include <stepwise/solvers/run_support.hpp>

#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_butcher_dirk.h>
#include <arkode/arkode_butcher_erk.h>
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nonlinearsolver.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>

namespace stepwise::sundials {

struct ContextFree { void operator()(SUNContext c) const { SUNContext_Free(&c); } };
struct VectorFree { void operator()(_generic_N_Vector* v) const { N_VDestroy(v); } };
struct MatrixFree { void operator()(_generic_SUNMatrix* m) const { SUNMatDestroy(m); } };
struct LinSolFree { void operator()(_generic_SUNLinearSolver* s) const { SUNLinSolFree(s); } };
struct NonlinSolFree { void operator()(_generic_SUNNonlinearSolver* s) const { SUNNonlinSolFree(s); } };
using ContextPtr = std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextFree>;
using VectorPtr = std::unique_ptr<_generic_N_Vector, VectorFree>;
using MatrixPtr = std::unique_ptr<_generic_SUNMatrix, MatrixFree>;
using LinSolPtr = std::unique_ptr<_generic_SUNLinearSolver, LinSolFree>;
using NonlinSolPtr = std::unique_ptr<_generic_SUNNonlinearSolver, NonlinSolFree>;
// an integrator's memory (CVODE's, ARKStep's)
struct CvodeFree { void operator()(void* mem) const { CVodeFree(&mem); } };
struct ArkodeFree { void operator()(void* mem) const { ARKStepFree(&mem); } };
using CvodePtr = std::unique_ptr<void, CvodeFree>;
using ArkodePtr = std::unique_ptr<void, ArkodeFree>;

// an arkode-* method's Butcher tables, by its name in the table (ARKODE_ERK_NONE or ARKODE_DIRK_NONE for the
// part it lacks): for a driver of ARKODE beside the table's adapter (solvers/distributed_lines); empty for
// another name. Defined with the table, in methods/arkode.cpp
struct ArkodeTables {
  ARKODE_ERKTableID erk;
  ARKODE_DIRKTableID dirk;
};
std::optional<ArkodeTables> arkode_tables(std::string_view method);

// a return flag's name by a module's *GetReturnFlagName (which allocates it), "unknown" where it has none
std::string return_flag_name(char* (*name_of)(long), long flag);

// what the C callbacks reach through user_data
struct Callbacks {
  const CountedSystem* system = nullptr;
  const ImexSplit* split = nullptr;  // an IMEX run: the Jacobian callbacks give df_I/dy
  bool non_finite = false;           // f produced a non-finite value: the run has blown up
  std::string last_error;            // the solver's own message for the last failure
  std::string event_error;           // an event's g was not finite: which, and when (the failure's reason)
  double event_error_t = 0;          // that time
  Eigen::MatrixXd jac;               // dense df/dy scratch (n x n), sized by the first dense Jacobian call
  Eigen::SparseMatrix<double> sparse_jac;  // sparse df/dy scratch, fixed pattern
  Eigen::VectorXd projected;         // projection scratch
  // the level each event's next crossing is measured from (roots() gives g - level): 0, but for an event whose
  // handler left its g where the root put it, a hair from zero, that value, so that the crossing the state starts
  // from is not found again (output_loop); one entry an event, sized by output_loop
  Eigen::VectorXd event_levels;
};

// f, and the two parts of an IMEX split (each call of a part counted as one call of f)
int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data);
int explicit_part(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data);
int implicit_part(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data);
// a SUNDIALS context and a serial vector holding y0: SUNContext_Create's return code (0: made)
int serial_state(const Eigen::VectorXd& y0, ContextPtr& context, VectorPtr& y);
// df/dy (df_I/dy for an IMEX run) into a dense or a sparse SUNMatrix; one Jacobian evaluation each
int dense_jacobian(sunrealtype t, N_Vector y, N_Vector, SUNMatrix J, void* user_data, N_Vector, N_Vector, N_Vector);
int sparse_jacobian(sunrealtype t, N_Vector y, N_Vector, SUNMatrix J, void* user_data, N_Vector, N_Vector, N_Vector);
// the events' g, each less its level (Callbacks::event_levels)
int roots(sunrealtype t, N_Vector y, sunrealtype* gout, void* user_data);
void error_handler(int, const char* module, const char* function, char* msg, void* user_data);

// the system's sparse Jacobian pattern (df_I/dy's for an IMEX run) at (t0, y0), with the diagonal made
// explicit: SUNDIALS 6.4 forms I - gamma J by rebuilding the whole matrix for every missing diagonal entry,
// a cost growing as n^2
void initial_pattern(Callbacks& c, double t0, const Eigen::VectorXd& y0);
// a CSC SUNMatrix sized for the pattern initial_pattern() left in c.sparse_jac
SUNMatrix sparse_matrix(const Callbacks& c, SUNContext context);

// the sparse direct solver of Newton's linear systems on `matrix`'s pattern (sunlinsol_umfpack.cpp): KLU (AMD
// ordering) below umfpack_from unknowns, UMFPACK's multifrontal LU from there (a 2-D grid's fill); null where it
// could not be made, `made_by` naming the call
inline constexpr sunindextype umfpack_from = 16384;
SUNLinearSolver sparse_solver(N_Vector y, SUNMatrix matrix, SUNContext context, const char*& made_by);

// one adapter's entry points for the output loop below
struct Driver {
  std::string_view method;       // the method's name, for messages
  std::string_view evolve_call;  // "CVode", "ARKStepEvolve", ...
  int root_return = 0;           // the code the evolve call returns at a root
  // to the target (one_step: one step toward it, not past it: the steps a trajectory of steps records)
  std::function<int(double target, N_Vector y, double& t, bool one_step)> evolve;
  std::function<void(int* found)> root_info;
  std::function<int(double t, N_Vector y)> reinit;  // restart at (t, y) after an event changed y
  // the solution at t inside the last step, from the solver's interpolant (*GetDky), into y (and IDA's y')
  std::function<int(double t, N_Vector y)> state_at;
  std::function<void()> add_counters;               // the solver's counters into the result (before a reinit resets them)
  std::function<std::string(long code)> flag_name;
};

// steps through every output time, handling events (their handlers change the state, then the solver is
// re-initialised there), recording the outputs, and ending the run as diverged or failed where it does
void output_loop(const Driver& driver, Callbacks& callbacks, N_Vector y, double t0, std::span<const double> t_out,
                 const StepControl& control, RunResult& result);

}  // namespace stepwise::sundials
