#include "report/cost_model.hpp"

#include "models/model.hpp"
#include "solvers/capabilities/imex_split.hpp"
#include "solvers/capabilities/mass_spring.hpp"
#include "solvers/method_table.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace stepwise {

bool solves_newton_systems(const Method& method) {
  // (fast-mass-spring, which needs a spring network, solves its prefactored system ten times a step)
  return method.dense != DenseMatrices::none || method.needs.type == needs_mass_spring.type || method.needs.type == needs_spring_network.type ||
         method.needs.type == needs_imex_split.type;
}

double expected_run_ns(const Method& method, const StepControl& control, double t_end, double time_scale, double n) {
  const double order = std::max(1, method.order.max);
  const double steps = control.dt ? t_end / *control.dt : 10 * t_end / time_scale * std::pow(control.rtol, -1 / (order + 1));
  const bool implicit = solves_newton_systems(method);
  const bool gpu = method.family == Family::gpu;
  const double stages = std::min(order, 8.0);
  // a step's fixed part by whose code steps: a library's Newton iterations ~600 ns a stage (SUNDIALS' DIRK
  // and BDF, GSL's implicit steppers, on the pendulum), else SUNDIALS' ~250 ns, GSL's ~100 ns, a hand-written or
  // Boost.Odeint loop's ~10 ns (the convergence sweep's runs, measured)
  const bool sundials = method.family == Family::cvode || method.family == Family::arkode, gsl = method.family == Family::gsl;
  const double fixed = implicit && (sundials || gsl) ? 600 * stages : sundials ? 250 : gsl ? 100 : 10;
  // and per entry and stage: the right-hand side's ~10 ns (five times that for Newton's iterations), and SUNDIALS'
  // own vector operations' ~15 ns more (ARKODE's explicit stages on the 24^2 shear layer, n = 1728: 62-72 us a
  // right-hand side where GSL's and the hand-written steppers' take 38; the full report's work-precision points)
  const double per_entry = 10 * (implicit ? 5 : 1) + (sundials ? 15 : 0);
  return steps * (fixed + per_entry * n * stages + (gpu ? 1e4 : 0));
}

double machine_slowness() {
  const auto model = make_model("pendulum", {});
  const auto integrator = make_integrator("rk4", StepControl::fixed(1e-3));
  const std::vector<double> t_out{10.0};
  integrator->solve(*model, 0, model->initial_state(), t_out);  // the warm-up
  // the mean over ~20 ms of runs, not the least run: a machine shared with other work runs the sweeps slower
  // too, which a least run of 0.35 ms, inside one time slice, does not see
  constexpr int runs = 60;
  const auto start = std::chrono::steady_clock::now();
  for (int run = 0; run < runs; ++run)
    if (integrator->solve(*model, 0, model->initial_state(), t_out).status != Status::ok) return 1;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / runs;
  // the reference machine's time for these runs (the one the report's time promises are made on), at whose speed
  // the time-left lines at 0.4 ns a unit come within a factor of two of the truth
  constexpr double reference_seconds = 350e-6;
  return seconds / reference_seconds;
}

double expected_contact_ns(double steps, double bodies) { return steps * bodies * bodies * 3.4e3; }

double expected_frame_ns(double balls, double water_points, double other_primitives) {
  return 1.2e7 + 4e3 * balls + 1e3 * water_points + 2e3 * other_primitives;
}

}  // namespace stepwise
