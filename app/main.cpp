// The stepwise program: the command line (app/cli.hpp) inside the process's signal handling and, under mpirun, its
// MPI session.
#include "cli.hpp"
#include "run/interrupt.hpp"
#include "run/message.hpp"
#include "run/ranks.hpp"

#include <exception>
#include <optional>

int main(int argc, char** argv) {
  // the signals first: one that comes while MPI starts ends the run as any other does
  stepwise::interrupt::install();
  std::optional<stepwise::ranks::Session> mpi;  // MPI under mpirun only (run/ranks.hpp)
  try {
    mpi.emplace(argc, argv);
  } catch (const std::exception& e) {
    stepwise::print_error("", e.what());
    return 1;
  }
  stepwise::interrupt::install();
  const int code = stepwise::command_line(argc, argv);
  // an interruption under way ends the process itself, with its status and its line
  stepwise::interrupt::settle();
  return code;
}
