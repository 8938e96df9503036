// `stepwise run` on MPI ranks: which runs are split among them, and the split run. Under mpirun, wave-fd on a
// water model (water-drop, standing-wave, pool) runs on a 2D Cartesian decomposition of its grid
// (solvers/distributed_wave.hpp), each rank stepping its block, the same bits as one process; rank 0 gathers
// the state at the output times and at the end and writes the outputs from it as one process does (so rank 0
// needs the whole grid's (z, v) at those times: the step is distributed, the summaries are not). Anything else
// runs on rank 0 alone, which says so in one line.
#pragma once

#include <stepwise/run/measure.hpp>
#include <stepwise/run/prepare.hpp>

#include <functional>
#include <memory>
#include <string>

namespace stepwise {

class DistributedWave;

// "" when this run is split among the ranks under mpirun, else why not (the model or the method)
std::string not_distributed(const PreparedRun& p);

class DistributedRun {
 public:
  // p's grid decomposed over every rank (collective); DecompositionError (solvers/distributed_wave.hpp) when
  // a side has more ranks than points, before any work
  explicit DistributedRun(const PreparedRun& p);
  ~DistributedRun();
  DistributedRun(const DistributedRun&) = delete;
  DistributedRun& operator=(const DistributedRun&) = delete;

  // the run, on every rank (collective): `sink` (rank 0's, as a step control's) gets the model's summary of
  // the whole grid at each output time; rank 0's result holds the whole grid's final state, the others' their
  // block's. A sink that ends the run ends it on every rank
  Measured run(const PreparedRun& p, const std::function<std::string(double t, const Eigen::VectorXd& sample)>& sink);

 private:
  std::unique_ptr<DistributedWave> grid_;
};

}  // namespace stepwise
