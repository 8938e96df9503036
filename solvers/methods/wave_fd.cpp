// wave-fd: the seeds' three-level scheme for the damped wave equation on the CPU, in double
// (solvers/three_level_wave.hpp keeps the levels; wave_step.hpp has the cell's formula and the limit).
#include "solvers/three_level_wave.hpp"

namespace stepwise {

namespace {

class WaveFd final : public ThreeLevelWaveStepper {
 public:
  using ThreeLevelWaveStepper::ThreeLevelWaveStepper;

 private:
  bool advance(const WaveCoefficients& k, const double* z_prev, const double* z, double* z_next, bool, std::string&) override {
    const int n = grid().points;
    for (int i = 1; i < n - 1; ++i)
      for (int j = i * n + 1; j < (i + 1) * n - 1; ++j) z_next[j] = wave_cell(k, z[j], z_prev[j], neighbour_sum(z, j, n));
    return true;
  }
};

}  // namespace

void register_wave_fd_methods(MethodTable& table) {
  table.add({
      .name = "wave-fd",
      .family = Family::wave_fd,
      .source = Source::hand_written,
      .description = "explicit three-level finite differences for the damped wave equation (the seeds' scheme), fixed step",
      .order = {2, 2, "2"},
      .stepping = Stepping::fixed,
      .needs = needs_wave_grid,
      .on_ranks = OnRanks::split_grid,
      .make = fixed_steps([](const CountedSystem& system) { return std::make_unique<WaveFd>(system); }),
      .stability = {.wave_dt = wave_stable_dt},
  });
}


}  // namespace stepwise
