#include "reference.hpp"

#include "run/measure.hpp"

#include <fmt/format.h>

#include <array>
#include <stdexcept>

namespace stepwise {
namespace {

// at 1e-13 an eighth-order pair takes ~100 steps per unit time on the pendulum; 2e5 steps is far beyond any
// non-stiff scene here and stops an explicit run on a stiff one in a fraction of a second
constexpr long explicit_step_budget = 200'000;
constexpr double explicit_rtol = 1e-13, stiff_rtol = 1e-12;

}  // namespace

Reference converged_reference(const Model& model, double t_end) {
  struct Pair {
    std::array<const char*, 2> methods;
    double rtol;
    long max_steps;
  };
  std::string why;
  for (const Pair& pair : {Pair{{"gsl-rk8pd", "verner98"}, explicit_rtol, explicit_step_budget}, Pair{{"cvode-bdf", "gsl-bsimp"}, stiff_rtol, 2'000'000}}) {
    StepControl control = StepControl::adaptive(pair.rtol, 1e-3 * pair.rtol);
    control.max_steps = pair.max_steps;
    std::array<Eigen::VectorXd, 2> y;
    bool finished = true;
    for (size_t k = 0; k < 2 && finished; ++k) {
      const Measured m = run_and_measure(model, pair.methods[k], control, t_end, t_end);
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
