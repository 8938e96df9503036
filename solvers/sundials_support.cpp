#include "sundials_support.hpp"

#include "events.hpp"

#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cstdlib>
#include <limits>

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
    const auto k = static_cast<Eigen::Index>(i);
    gout[i] = events[i].g(t, state) - (k < c.event_levels.size() ? c.event_levels[k] : 0.0);
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

namespace {

// SUNDIALS returns a root where g has reached zero or just crossed it (its rootfinder's right end, within its
// tolerance of 100 eps (|t| + |h|)): a ball a hair below the floor. An action that turns the motion back then
// starts from the far side, and the crossing back is found as a new root (a bounce reversed again, 27 times). So
// the state is carried back, on the solver's interpolant, to the left root: the latest time before the returned
// one at which every fired event's g is still on the side it came from, or zero (DifferentialEquations.jl's
// LeftRootFind). `found`: SUNDIALS' rootsfound, +1 where g was rising (it came from below), -1 falling.
// (Each g less its level, as SUNDIALS sees it: Callbacks::event_levels)
void left_root(const Driver& driver, const Callbacks& callbacks, std::span<const Event> events, std::span<const int> found, double& t, N_Vector y) {
  if (!driver.state_at) return;
  const auto crossed_at = [&](double time) {
    const Eigen::VectorXd state = view(y);  // the events read a state of the system's size or more (IDA's unknowns go on)
    for (size_t i = 0; i < events.size(); ++i)
      if (found[i] != 0 && (events[i].g(time, state) - callbacks.event_levels[static_cast<Eigen::Index>(i)]) * found[i] > 0) return true;
    return false;
  };
  if (!crossed_at(t)) return;
  // back from the root by doubling until no fired event has crossed (a failing interpolation: outside the last
  // step, so the root stays where SUNDIALS put it), then bisect between
  const double eps = std::numeric_limits<double>::epsilon();
  double right = t, left = t, back = 4 * eps * std::max(1.0, std::abs(t));
  for (int k = 0;; ++k, back *= 2) {
    left = t - back;
    if (k == 60 || driver.state_at(left, y) != 0) {
      (void)driver.state_at(t, y);
      return;
    }
    if (!crossed_at(left)) break;
    right = left;
  }
  while (true) {
    const double middle = 0.5 * (left + right);
    if (middle <= left || middle >= right) break;
    if (driver.state_at(middle, y) != 0) break;
    (crossed_at(middle) ? right : left) = middle;
  }
  (void)driver.state_at(left, y);
  t = left;
}

}  // namespace

void output_loop(const Driver& driver, Callbacks& callbacks, N_Vector y, double t0, std::span<const double> t_out,
                 const StepControl& control, RunResult& result) {
  const auto events = events_of(*callbacks.system);
  std::vector<int> found(events.size());
  std::vector<size_t> fired;
  Eigen::VectorXd g_before;  // the events' g at a root, before its handlers
  callbacks.event_levels = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(events.size()));
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
      left_root(driver, callbacks, events, found, t, y);
      fired.clear();
      for (size_t i = 0; i < found.size(); ++i)
        if (found[i] != 0) fired.push_back(i);
      Eigen::VectorXd y_event = ym;
      event_values(events, t, y_event, g_before);
      stop = !handle_events(result, events, fired, t, y_event);
      ym = y_event;
      if (stop) break;
      // the next crossing of an event whose handlers left its g where the root put it (a bounce that turns the
      // velocity alone; an event that only counts) is measured from there: a left root a hair short of zero is
      // then no crossing still to come. Where they moved it (onto the zero, or away), from zero
      for (const size_t i : fired) {
        const auto k = static_cast<Eigen::Index>(i);
        const double g_after = events[i].g(t, y_event);
        callbacks.event_levels[k] = g_after == g_before[k] ? g_after : 0.0;
      }
      driver.add_counters();
      if (const int re = driver.reinit(t, y)) {
        code = re;
        break;
      }
      if (t >= target || same_instant(t, target)) {
        t = std::max(t, target);
        break;
      }
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
