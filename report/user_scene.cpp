#include "user_scene.hpp"

#include "verification/stability.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace stepwise {

double spectrum_time_scale(const Model& model, double t_end) {
  const Eigen::VectorXcd spectrum = leading_spectrum(model, 0, model.initial_state());
  const double fastest = spectrum.size() ? spectrum.cwiseAbs().maxCoeff() : 0.0;
  if (!(fastest > 0) || !std::isfinite(fastest)) return t_end / 16;
  // at least 16 steps of the run, at most 2^30
  const double halvings = std::clamp(std::ceil(std::log2(t_end * fastest)), 4.0, 30.0);
  return t_end / std::pow(2.0, halvings);
}

StudyScene user_study_scene(const RunOptions& options, PreparedRun* prepared) {
  PreparedRun p = prepare_run(options);
  StudyScene scene;
  scene.label = p.scene.name;
  scene.model = p.scene.model;
  scene.params = p.params;
  scene.t_end = p.t_end;
  scene.time_scale = spectrum_time_scale(*p.model, p.t_end);
  // the frame: twice the state's largest entry at the start (a length scale for the animation target)
  scene.frame_extent = 2 * std::max(1.0, p.model->initial_state().cwiseAbs().maxCoeff());
  scene.factory = [options, file = p.scene] { return prepare_run(options, file).model; };
  if (const auto& pde = p.scene.pde) {
    scene.on_grid = [options, file = p.scene](int points, int order) {
      RunOptions refined = options;
      if (points > 0) refined.sets.push_back(fmt::format("points={}", points));
      refined.sets.push_back(fmt::format("order={}", order));
      return prepare_run(refined, file).model;
    };
    scene.periodic = std::all_of(pde->boundary.begin(), pde->boundary.end(), [&](const auto& b) {
      return b.second.periodic[0] && (pde->dimension == 1 || b.second.periodic[1]);
    });
  }
  if (prepared) *prepared = std::move(p);
  return scene;
}

}  // namespace stepwise
