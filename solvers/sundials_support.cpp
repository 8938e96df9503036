#include "sundials_support.hpp"

#include "events.hpp"

#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cstdlib>

namespace stepwise::sundials {

std::string return_flag_name(char* (*name_of)(long), long flag) {
  char* name = name_of(flag);
  std::string s = name ? name : "unknown";
  std::free(name);
  return s;
}
namespace {

Eigen::Map<const Eigen::VectorXd> view(N_Vector v) {
  return {N_VGetArrayPointer(v), static_cast<Eigen::Index>(N_VGetLength(v))};
}
Eigen::Map<Eigen::VectorXd> view_mut(N_Vector v) {
  return {N_VGetArrayPointer(v), static_cast<Eigen::Index>(N_VGetLength(v))};
}

// 0 when the call's result is finite, else 1 (recoverable: the solver cuts the step) and the run is marked
int finite_or_retry(Callbacks& c, const Eigen::Map<Eigen::VectorXd>& out) {
  if (out.allFinite()) return 0;
  c.non_finite = true;
  return 1;
}

void with_diagonal(Eigen::SparseMatrix<double>& J) {
  Eigen::SparseMatrix<double> zero(J.rows(), J.cols());
  zero.setIdentity();
  zero.coeffs().setZero();
  J = J + zero;
  J.makeCompressed();
}

void evaluate_sparse(const Callbacks& c, double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::SparseMatrix<double>& J) {
  if (c.split) c.split->implicit_jacobian(t, y, J);
  else c.system->as<SparseJacobian>()->sparse_jacobian(t, y, J);
}

}  // namespace

int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data) {
  auto& c = *static_cast<Callbacks*>(user_data);
  auto out = view_mut(ydot);
  c.system->rhs(t, view(y), out);
  return finite_or_retry(c, out);
}

namespace {

// one part of the split, counted as one call of f
template <ImexSplit::Part ImexSplit::*part>
int split_part(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data) {
  auto& c = *static_cast<Callbacks*>(user_data);
  auto out = view_mut(ydot);
  ++c.system->stats().rhs_evals;
  (c.split->*part)(t, view(y), out);
  return finite_or_retry(c, out);
}

}  // namespace

int explicit_part(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data) {
  return split_part<&ImexSplit::explicit_part>(t, y, ydot, user_data);
}

int implicit_part(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data) {
  return split_part<&ImexSplit::implicit_part>(t, y, ydot, user_data);
}

int serial_state(const Eigen::VectorXd& y0, ContextPtr& context, VectorPtr& y) {
  SUNContext raw = nullptr;
  if (const int code = SUNContext_Create(nullptr, &raw); code != 0) return code;
  context.reset(raw);
  y.reset(N_VNew_Serial(static_cast<sunindextype>(y0.size()), context.get()));
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(y.get()), y0.size()) = y0;
  return 0;
}

int dense_jacobian(sunrealtype t, N_Vector y, N_Vector, SUNMatrix J, void* user_data, N_Vector, N_Vector, N_Vector) {
  auto& c = *static_cast<Callbacks*>(user_data);
  const auto n = static_cast<Eigen::Index>(N_VGetLength(y));
  c.jac.resize(n, n);
  c.system->as<DenseJacobian>()->jacobian(t, view(y), c.jac);
  ++c.system->stats().jac_evals;
  // SUNDIALS dense matrices are column-major, like Eigen's default
  Eigen::Map<Eigen::MatrixXd>(SUNDenseMatrix_Data(J), n, n) = c.jac;
  return c.jac.allFinite() ? 0 : 1;
}

int sparse_jacobian(sunrealtype t, N_Vector y, N_Vector, SUNMatrix J, void* user_data, N_Vector, N_Vector, N_Vector) {
  auto& c = *static_cast<Callbacks*>(user_data);
  const auto n = static_cast<Eigen::Index>(N_VGetLength(y));
  evaluate_sparse(c, t, view(y), c.sparse_jac);
  ++c.system->stats().jac_evals;
  with_diagonal(c.sparse_jac);
  const auto nnz = c.sparse_jac.nonZeros();
  if (nnz > SUNSparseMatrix_NNZ(J)) SUNSparseMatrix_Reallocate(J, nnz);
  std::copy_n(c.sparse_jac.outerIndexPtr(), n + 1, SUNSparseMatrix_IndexPointers(J));
  std::copy_n(c.sparse_jac.innerIndexPtr(), nnz, SUNSparseMatrix_IndexValues(J));
  std::copy_n(c.sparse_jac.valuePtr(), nnz, SUNSparseMatrix_Data(J));
  return 0;
}

int roots(sunrealtype t, N_Vector y, sunrealtype* gout, void* user_data) {
  auto& c = *static_cast<Callbacks*>(user_data);
  const Eigen::VectorXd state = view(y);
  const auto events = events_of(*c.system);
  for (size_t i = 0; i < events.size(); ++i) {
    gout[i] = events[i].g(t, state);
    if (!std::isfinite(gout[i])) {
      c.event_error = not_finite_event(events[i], gout[i], t);
      c.event_error_t = t;
      return 1;
    }
  }
  return 0;
}

void error_handler(int, const char* module, const char* function, char* msg, void* user_data) {
  static_cast<Callbacks*>(user_data)->last_error = fmt::format("{}:{}: {}", module, function, msg);
}

void initial_pattern(Callbacks& c, double t0, const Eigen::VectorXd& y0) {
  evaluate_sparse(c, t0, y0, c.sparse_jac);
  with_diagonal(c.sparse_jac);
}

SUNMatrix sparse_matrix(const Callbacks& c, SUNContext context) {
  const auto n = c.sparse_jac.rows();
  return SUNSparseMatrix(n, n, std::max<sunindextype>(1, c.sparse_jac.nonZeros()), CSC_MAT, context);
}

void output_loop(const Driver& driver, Callbacks& callbacks, N_Vector y, double t0, std::span<const double> t_out,
                 const StepControl& control, RunResult& result) {
  const auto events = events_of(*callbacks.system);
  std::vector<int> found(events.size());
  std::vector<size_t> fired;
  const auto n = static_cast<Eigen::Index>(callbacks.system->size());  // the state, leading y (IDA's unknowns go on)
  Eigen::Map<Eigen::VectorXd> ym(N_VGetArrayPointer(y), n);
  const double bound = divergence_bound(control, ym);
  double t = t0;
  bool stop = false;  // a terminal event or Zeno ended the run
  for (const double target : t_out) {
    int code = 0;
    while (true) {
      code = driver.evolve(target, y, t, control.record_steps);
      if (code < 0) break;
      if (code != driver.root_return) {
        // one step at a time: each step's end joins the trajectory until the output time is reached
        if (!control.record_steps || t >= target) break;
        if (has_diverged(ym, bound) || !record_output(result, control, t, ym)) break;
        continue;
      }
      // every event SUNDIALS found at this root (its rootsfound: all whose g vanishes within its root tolerance),
      // handled in the order the system declares them
      driver.root_info(found.data());
      fired.clear();
      for (size_t i = 0; i < found.size(); ++i)
        if (found[i] != 0) fired.push_back(i);
      Eigen::VectorXd y_event = ym;
      stop = !handle_events(result, events, fired, t, y_event);
      ym = y_event;
      if (stop) break;
      driver.add_counters();
      if (const int re = driver.reinit(t, y)) {
        code = re;
        break;
      }
      if (t >= target) break;
      if (control.record_steps && !record_output(result, control, t, ym)) break;
    }
    if (stop) {
      if (control.record_steps && result.status == Status::ok) (void)record_output(result, control, t, ym);
      break;
    }
    if (result.status != Status::ok) break;
    if (code < 0) {
      if (callbacks.non_finite || has_diverged(ym, bound)) mark_diverged(result, t);
      else {
        // an event's g not finite fails the run where it was found, for that reason; else the solver's own
        const bool event = !callbacks.event_error.empty();
        mark_failed(result, event ? callbacks.event_error_t : t,
                    fmt::format("{}: {} returned {} ({}) at t = {:.9g}: {}", driver.method, driver.evolve_call, code, driver.flag_name(code), t,
                                event ? callbacks.event_error : callbacks.last_error));
      }
      break;
    }
    if (has_diverged(ym, bound)) {
      mark_diverged(result, t);
      break;
    }
    if (!record_output(result, control, t, ym)) break;
  }
  driver.add_counters();
}

}  // namespace stepwise::sundials
