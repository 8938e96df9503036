#include "run_command.hpp"

#include "run/atomic_write.hpp"
#include "run/interrupt.hpp"
#include "run/measure.hpp"
#include "run/message.hpp"
#include "run/ranks.hpp"
#include "run/run_outputs.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <memory>

namespace stepwise {

int run_command(const RunOptions& options) {
  // under mpirun: no model is distributed yet, so rank 0 runs the scene as one process would (docs/usage.md)
  if (ranks::idle_here("run")) return 0;
  PreparedRun p;
  std::unique_ptr<RunOutputs> outputs;
  try {
    p = prepare_run(options);
    ensure_writable_directory(options.out);
    check_output_fits(options.out, p);
    interrupt::remove_stale(options.out);
    outputs = std::make_unique<RunOutputs>(options.out, p);
  } catch (const InputError& e) {
    print_error("run", e.what());
    return 2;
  } catch (const BadMethod& e) {
    print_error("run", fmt::format("--method: {}", e.what()));
    return 2;
  } catch (const std::runtime_error& e) {
    print_error("run", fmt::format("--out: {}", e.what()));
    return 2;
  }

  // the rows go to the trajectory's file as they come
  p.control.sink = [&outputs](double t, const Eigen::VectorXd& sample) { return outputs->sample(t, sample); };
  Measured m = run_and_measure(*p.model, p.method, p.control, p.t_end, p.output_dt);
  if (m.error && !std::isfinite(*m.error)) {
    m.result.status = Status::diverged;
    m.result.message = fmt::format("diverged at t = {:.9g}: the error against the exact solution overflowed ({})", p.t_end, *m.error);
    m.result.t_stop = p.t_end;
  }
  try {
    outputs->finish(m);
  } catch (const std::runtime_error& e) {
    print_error("run", e.what());
    return 1;
  }
  if (m.result.status != Status::ok) {
    // a backend's failure names its method already
    const bool named = m.result.message.starts_with(p.method + ":");
    print_error("run", named ? m.result.message : fmt::format("{}: {}", p.method, m.result.message));
    return 1;
  }
  return 0;
}

}  // namespace stepwise
