#include "run/distributed_run.hpp"

#include "run/ranks.hpp"
#include "solvers/distributed_wave.hpp"
#include "solvers/method_table.hpp"

#include <fmt/format.h>

namespace stepwise {

std::string not_distributed(const PreparedRun& p) {
  if (!p.model->as<WaveBlocksView>() || !p.model->as<WaveGridView>())
    return fmt::format("model '{}' is not split among ranks: only the water's grid is", p.model->name());
  if (const Method* m = find_method(p.method); !m || m->on_ranks != OnRanks::split_grid)
    return fmt::format("method '{}' is not split among ranks: only wave-fd is", p.method);
  return {};
}

DistributedRun::DistributedRun(const PreparedRun& p) {
  const int n = p.model->as<WaveGridView>()->points;
  grid_ = std::make_unique<DistributedWave>(n, n, WaveCoefficients{});
}

DistributedRun::~DistributedRun() = default;

Measured DistributedRun::run(const PreparedRun& p, const std::function<std::string(double t, const Eigen::VectorXd& sample)>& sink) {
  const Model& model = *p.model;
  const bool leader = ranks::rank() == 0;
  Measured m;
  m.t_out = output_times(p.t_end, p.output_dt);
  StepControl control = p.control;
  // at an output time rank 0 takes the whole grid and samples it as one process would
  control.observe = [&](const Eigen::VectorXd& block) {
    const Eigen::VectorXd whole = grid_->gather_state(block);
    return leader ? model.summary(whole) : Eigen::VectorXd();
  };
  control.sink = [&](double t, const Eigen::VectorXd& sample) {
    std::string stop = leader && sink ? sink(t, sample) : std::string();
    if (!ranks::all_agree(stop.empty()) && stop.empty()) stop = "rank 0 ended the run";
    return stop;
  };
  m.result = wave_fd_distributed(*grid_, *model.as<WaveGridView>(), *model.as<WaveBlocksView>(), control, m.t_out);
  m.result.y_stop = grid_->gather_state(m.result.y_stop);
  if (leader) measure_error(model, m, p.t_end);
  return m;
}

}  // namespace stepwise
