#include "reference.hpp"

#include "run/measure.hpp"
#include "solvers/method_table.hpp"

#include <fmt/format.h>

#include <array>
#include <limits>
#include <stdexcept>

namespace stepwise {
namespace {

// at 1e-13 an eighth-order pair takes ~100 steps per unit time on the pendulum; 2e5 steps is far beyond any
// non-stiff scene here and stops an explicit run on a stiff one in a fraction of a second
constexpr long explicit_step_budget = 200'000;
constexpr double explicit_rtol = 1e-13, stiff_rtol = 1e-12;

// `control` for a reference run of `method` under `limit`: each step's end goes to a sink that ends the run (as
// diverged) once the deadline has passed, noting the time reached, or once its pace says it would pass its step
// budget twice over (from its 200th step on), and says the progress about once a second. The steps are those
// taken without it
StepControl limited(StepControl control, std::string method, double t_end, const ReferenceLimit& limit, double& reached) {
  using Clock = std::chrono::steady_clock;
  control.record_steps = true;
  control.sink = [method, t_end, &limit, &reached, said = Clock::now(), steps = 0L, max_steps = control.max_steps](double t, const Eigen::VectorXd&) mutable
      -> std::string {
    reached = t;
    const auto now = Clock::now();
    if (now > limit.deadline) return "out of time";
    // at this pace the run would pass its step budget (a stiff system held to an explicit method's tiny steps): it
    // is ended now rather than when it has spent the budget's time on the steps
    if (++steps >= 200 && t > 0 && static_cast<double>(steps) * t_end / t > 2 * static_cast<double>(max_steps))
      return fmt::format("at its pace ({} steps to t = {:.3g}) it would pass its budget of {} steps before t_end", steps, t, max_steps);
    if (limit.progress && now - said > std::chrono::seconds(1)) {
      said = now;
      limit.progress(fmt::format("the reference: {} at t = {:.4g} of {:.4g} s", method, t, t_end));
    }
    return {};
  };
  return control;
}

}  // namespace

Measured reference_run(const Model& model, const std::string& method, const StepControl& control, double t_end, const ReferenceLimit* limit,
                       double spent_before, int runs_after, const std::string& what) {
  using Clock = std::chrono::steady_clock;
  if (!limit) return run_and_measure(model, method, control, t_end, t_end);
  const auto run_start = Clock::now();
  if (limit->progress) limit->progress(fmt::format("{}: {} at rtol {:.0e} from t = 0 to {:.4g} s", what, method, control.rtol, t_end));
  double reached = 0;
  Measured m = run_and_measure(model, method, limited(control, method, t_end, *limit, reached), t_end, t_end);
  if (Clock::now() > limit->deadline && m.result.status != Status::ok) {
    // this run's pace to t_end, and the runs still to make at the same pace
    const double run_seconds = std::chrono::duration<double>(Clock::now() - run_start).count();
    const double whole_run = reached > 0 ? run_seconds * t_end / reached : std::numeric_limits<double>::infinity();
    throw ReferenceOutOfTime(fmt::format("{} ({} at rtol {:.0e}) reached t = {:.4g} of {:.4g} s in {:.3g} s", what, method, control.rtol, reached, t_end,
                                         run_seconds),
                             spent_before + whole_run * static_cast<double>(1 + runs_after));
  }
  return m;
}

Reference converged_reference(const Model& model, double t_end, const ReferenceLimit* limit) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  struct Pair {
    std::array<const char*, 2> methods;
    double rtol;
    long max_steps;
  };
  std::string why;
  // GSL's extrapolation factors a dense n x n matrix at every step: beyond a few hundred unknowns (a 16 MiB matrix)
  // the stiff pair's one-step code is RODAS5, which factors the sparse Jacobian where the model has one
  const Method& bsimp = *find_method("gsl-bsimp");
  const char* one_step = dense_matrix_bytes(bsimp, model) <= (1 << 24) ? "gsl-bsimp" : "rodas5";
  const Pair explicit_pair{{"gsl-rk8pd", "verner98"}, explicit_rtol, explicit_step_budget}, stiff_pair{{"cvode-bdf", one_step}, stiff_rtol, 2'000'000};
  for (const Pair& pair : {explicit_pair, stiff_pair}) {
    StepControl control = StepControl::adaptive(pair.rtol, 1e-3 * pair.rtol);
    control.max_steps = pair.max_steps;
    std::array<Eigen::VectorXd, 2> y;
    bool finished = true;
    for (size_t k = 0; k < 2 && finished; ++k) {
      const double spent = std::chrono::duration<double>(Clock::now() - start).count();
      const Measured m = reference_run(model, pair.methods[k], control, t_end, limit, spent, static_cast<int>(1 - k), "the reference");
      finished = m.result.status == Status::ok;
      if (!finished) why += fmt::format("{}{} at rtol {:.0e}: {}", why.empty() ? "" : "; ", pair.methods[k], pair.rtol, m.result.message);
      y[k] = m.result.y_stop;
    }
    if (!finished) continue;
    return {y[0], fmt::format("{} and {} at rtol {:.0e}", pair.methods[0], pair.methods[1], pair.rtol), max_norm_error(y[0], y[1]),
            pair.methods[0] != std::string_view("gsl-rk8pd")};
  }
  throw std::runtime_error(fmt::format("no reference run finished: {}", why));
}

}  // namespace stepwise
