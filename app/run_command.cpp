#include "run_command.hpp"

#include "run/atomic_write.hpp"
#include "run/measure.hpp"
#include "run/run_outputs.hpp"

#include <filesystem>
#include <iostream>

namespace stepwise {

int run_command(const RunOptions& options) {
  PreparedRun p;
  try {
    p = prepare_run(options);
    ensure_writable_directory(options.out);
  } catch (const InputError& e) {
    std::cerr << "stepwise run: " << e.what() << '\n';
    return 2;
  } catch (const BadMethod& e) {
    std::cerr << "stepwise run: --method: " << e.what() << '\n';
    return 2;
  } catch (const std::runtime_error& e) {
    std::cerr << "stepwise run: --out: " << e.what() << '\n';
    return 2;
  }

  Measured m = run_and_measure(*p.model, p.method, p.control, p.t_end, p.output_dt);
  const std::filesystem::path out(options.out);
  try {
    write_run_outputs(out, p, m);
  } catch (const std::runtime_error& e) {
    std::cerr << "stepwise run: " << e.what() << '\n';
    return 2;
  }
  if (m.result.status != Status::ok) {
    std::cerr << "stepwise run: " << p.method << ": " << m.result.message << '\n';
    return 1;
  }
  return 0;
}

}  // namespace stepwise
