#include "run_command.hpp"

#include "models/equations.hpp"
#include "models/pde.hpp"
#include "run/atomic_write.hpp"
#include "run/distributed_run.hpp"
#include "run/interrupt.hpp"
#include "run/measure.hpp"
#include "run/message.hpp"
#include "run/ranks.hpp"
#include "run/run_outputs.hpp"
#include "solvers/distributed_wave.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <memory>

namespace stepwise {

int run_command(const RunOptions& options) {
  // under mpirun, every rank prepares the run; wave-fd on a water scene is split among them, anything else
  // runs on rank 0 alone (run/distributed_run.hpp). Only rank 0 speaks and writes
  const bool leader = ranks::rank() == 0;
  const auto refuse = [leader](std::string_view message) {
    if (leader) print_error("run", message);
    return 2;
  };
  PreparedRun p;
  std::unique_ptr<RunOutputs> outputs;
  std::unique_ptr<DistributedRun> spread;
  int refused = 0;
  try {
    p = prepare_run(options);
    if (ranks::size() > 1) {
      if (const std::string why = not_distributed(p); !why.empty()) {
        if (ranks::idle_here("run", why)) return 0;
      } else {
        spread = std::make_unique<DistributedRun>(p);
        p.ranks = ranks::size();
      }
    }
    if (leader) {
      // what was chosen for the user, and what runs while a large system compiles
      if (!p.method_choice.empty()) fmt::print(stderr, "stepwise run: {}\n", p.method_choice);
      if (const auto e = equations_evaluation(*p.model); e && e->background && !e->compiled)
        fmt::print(stderr, "stepwise run: {} equations: {}\n", p.model->size(), e->detail);
      // every output checked before the directory is made or anything runs: a refusal leaves nothing behind
      check_writable_directory(options.out);
      check_output_fits(options.out, p);
      for (const char* name : {"trajectory.csv", "summary.json"}) check_replaceable_file(std::filesystem::path(options.out) / name);
      if (const PdeGrid* grid = pde_grid(*p.model)) {
        check_replaceable_file(std::filesystem::path(options.out) / "grid.csv");
        for (const auto& field : grid->fields) check_replaceable_file(std::filesystem::path(options.out) / fmt::format("field_{}.csv", field));
      }
      ensure_writable_directory(options.out);
      interrupt::remove_stale(options.out);
      outputs = std::make_unique<RunOutputs>(options.out, p);
    }
  } catch (const InputError& e) {
    refused = refuse(e.what());
  } catch (const BadMethod& e) {
    refused = refuse(fmt::format("--method: {}", e.what()));
  } catch (const DecompositionError& e) {
    refused = refuse(e.what());
  } catch (const std::runtime_error& e) {
    refused = refuse(fmt::format("--out: {}", e.what()));
  }
  // rank 0's outputs may fail where the others' preparation did not: the ranks of a split run agree first.
  // Rank 0 alone exits 2 (mpirun's status): a follower exiting non-zero first would have mpirun kill rank 0
  if (spread ? !ranks::all_agree(refused == 0) : refused != 0) return leader ? 2 : 0;

  Measured m;
  if (spread) {
    try {
      m = spread->run(p, [&outputs](double t, const Eigen::VectorXd& sample) { return outputs->sample(t, sample); });
    } catch (const std::runtime_error& e) {
      // an MPI call failed on this rank: the others would wait for it
      print_error("run", fmt::format("rank {}: {}", ranks::rank(), e.what()));
      ranks::abort_all(1);
    }
    // rank 0 says how the run ended and exits with its status (a follower exiting 1 first would have mpirun kill
    // rank 0 while it writes)
    if (!leader) return 0;
  } else {
    // the rows go to the trajectory's file as they come
    p.control.sink = [&outputs](double t, const Eigen::VectorXd& sample) { return outputs->sample(t, sample); };
    if (outputs->whole_states()) p.control.observe = [](const Eigen::VectorXd& y) { return y; };
    m = run_and_measure(*p.model, p.method, p.control, p.t_end, p.output_dt);
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
