// SUNDIALS' sparse direct solver for a Newton matrix: KLU (SUNDIALS' own, a left-looking LU made for circuit
// matrices, refactorised on its first pivots) below umfpack_from unknowns, and from there SuiteSparse's UMFPACK
// (multifrontal, on the BLAS) as a SUNLinearSolver of CSC matrices, its symbolic analysis once on the fixed pattern
// and its numeric factorisation at every setup: a 2-D grid's fill wants fronts (bench_pde, Gray-Scott's I - J: at
// 2 x 128^2 UMFPACK 0.36 s against KLU's refactorisation 0.53 s; at 2 x 64^2 KLU 51 ms against 74).
#include "sundials_support.hpp"

#include "blas_threads.hpp"

#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <umfpack.h>

#include <cstdint>
#include <type_traits>
#include <vector>

namespace stepwise::sundials {
namespace {

static_assert(std::is_same_v<sunindextype, SuiteSparse_long>, "UMFPACK's long interface reads SUNDIALS' indices in place");

struct Umfpack {
  void* symbolic = nullptr;
  void* numeric = nullptr;
  double control[UMFPACK_CONTROL]{};
  double info[UMFPACK_INFO]{};
  int last = SUNLS_SUCCESS;
  std::vector<double> b;  // b's copy where SUNDIALS solves in place (UMFPACK wants x and b apart)
};

Umfpack& content(SUNLinearSolver s) { return *static_cast<Umfpack*>(s->content); }

int setup(SUNLinearSolver s, SUNMatrix a) {
  Umfpack& u = content(s);
  if (SUNSparseMatrix_SparseType(a) != CSC_MAT) return u.last = SUNLS_ILL_INPUT;
  const sunindextype n = SUNSparseMatrix_Columns(a);
  const sunindextype* p = SUNSparseMatrix_IndexPointers(a);
  const sunindextype* i = SUNSparseMatrix_IndexValues(a);
  const double* x = SUNSparseMatrix_Data(a);
  if (!u.symbolic && umfpack_dl_symbolic(n, n, p, i, x, &u.symbolic, u.control, u.info) != UMFPACK_OK) return u.last = SUNLS_PACKAGE_FAIL_UNREC;
  if (u.numeric) umfpack_dl_free_numeric(&u.numeric);
  const int status = umfpack_dl_numeric(p, i, x, u.symbolic, &u.numeric, u.control, u.info);
  // a singular matrix: CVODE and ARKODE retry with a smaller step (a recoverable failure, as KLU's)
  if (status == UMFPACK_WARNING_singular_matrix) return u.last = SUNLS_LUFACT_FAIL;
  return u.last = status == UMFPACK_OK ? SUNLS_SUCCESS : SUNLS_PACKAGE_FAIL_UNREC;
}

int solve(SUNLinearSolver s, SUNMatrix a, N_Vector x, N_Vector b, sunrealtype) {
  Umfpack& u = content(s);
  double* to = N_VGetArrayPointer(x);
  const double* from = N_VGetArrayPointer(b);
  if (to == from) {
    u.b.assign(from, from + N_VGetLength(b));
    from = u.b.data();
  }
  const int status = umfpack_dl_solve(UMFPACK_A, SUNSparseMatrix_IndexPointers(a), SUNSparseMatrix_IndexValues(a), SUNSparseMatrix_Data(a), to, from,
                                      u.numeric, u.control, u.info);
  return u.last = status == UMFPACK_OK ? SUNLS_SUCCESS : SUNLS_PACKAGE_FAIL_UNREC;
}

int free_solver(SUNLinearSolver s) {
  if (!s) return SUNLS_SUCCESS;
  if (auto* u = static_cast<Umfpack*>(s->content)) {
    if (u->numeric) umfpack_dl_free_numeric(&u->numeric);
    if (u->symbolic) umfpack_dl_free_symbolic(&u->symbolic);
    delete u;
  }
  s->content = nullptr;
  SUNLinSolFreeEmpty(s);
  return SUNLS_SUCCESS;
}

SUNLinearSolver umfpack_solver(SUNContext context) {
  SUNLinearSolver s = SUNLinSolNewEmpty(context);
  if (!s) return nullptr;
  keep_blas_on_this_thread();
  auto* u = new Umfpack;
  umfpack_dl_defaults(u->control);
  // no iterative refinement: a Newton iteration corrects the solve as KLU's (which has none) is corrected
  u->control[UMFPACK_IRSTEP] = 0;
  s->content = u;
  s->ops->gettype = [](SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; };
  s->ops->getid = [](SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; };
  s->ops->initialize = [](SUNLinearSolver) { return static_cast<int>(SUNLS_SUCCESS); };
  s->ops->setup = setup;
  s->ops->solve = solve;
  s->ops->lastflag = [](SUNLinearSolver self) { return static_cast<sunindextype>(content(self).last); };
  s->ops->free = free_solver;
  return s;
}

}  // namespace

SUNLinearSolver sparse_solver(N_Vector y, SUNMatrix matrix, SUNContext context, const char*& made_by) {
  if (SUNSparseMatrix_Columns(matrix) >= umfpack_from) {
    made_by = "SUNLinSolNewEmpty (UMFPACK)";
    return umfpack_solver(context);
  }
  made_by = "SUNLinSol_KLU";
  SUNLinearSolver klu = SUNLinSol_KLU(y, matrix, context);
  // AMD rather than SUNDIALS' default COLAMD: the mass-spring and wave patterns are structurally symmetric, and
  // COLAMD's fill made the 32 x 32 flag's refactorisations 50% of an IMEX run
  if (klu && SUNLinSol_KLUSetOrdering(klu, 0) != SUNLS_SUCCESS) {
    made_by = "SUNLinSol_KLUSetOrdering";
    SUNLinSolFree(klu);
    return nullptr;
  }
  return klu;
}

}  // namespace stepwise::sundials
