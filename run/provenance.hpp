// What ran, written as provenance.json beside a study's or the report's CSVs: the ranks and threads, the
// commit, the compiler and the libraries' versions, the machine, the start and end times, and how evenly the
// ranks shared the sweeps.
#pragma once

#include <chrono>
#include <string>
#include <vector>

namespace stepwise {

struct Provenance {
  std::string command;                               // "report --quick", "study convergence"
  int threads = 1;                                   // threads per rank
  std::chrono::system_clock::time_point start, end;
  std::vector<double> rank_seconds;                  // each rank's busy seconds in the sweeps
  double slowness = 0;  // the machine's time for a fixed rk4 run over the reference machine's (report/cost_model.hpp; 0: not measured)
};

// the JSON text (2-space indented)
std::string provenance_json(const Provenance& p);

}  // namespace stepwise
