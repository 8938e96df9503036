// The scenes of the studies of accuracy against step and cost (convergence, work-precision, stability regions),
// the methods each sweeps, and the targets the recommendations read off the work-precision fronts.
#pragma once

#include <stepwise/report/studies.hpp>

#include <stepwise/models/model.hpp>
#include <stepwise/solvers/capabilities/distance_constraints.hpp>
#include <stepwise/solvers/capabilities/imex_split.hpp>
#include <stepwise/solvers/capabilities/mass_spring.hpp>
#include <stepwise/solvers/wave_step.hpp>
#include <stepwise/verification/convergence.hpp>
#include <stepwise/verification/reference.hpp>
#include <stepwise/run/measure.hpp>
#include <stepwise/verification/stability.hpp>
#include <stepwise/verification/tolerances.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>

namespace stepwise {

// a scene of the studies: a model with parameters, integrated from t = 0 to t_end
struct StudyScene {
  std::string label;
  std::string model;
  Params params;
  double t_end;
  double time_scale;    // fastest time scale (s): 1/w for the pendulum, 1/rate for the flow
  double frame_extent;  // m: the height of the world a rendered frame shows, for the half-pixel target
  bool dense = true;        // false: methods keeping dense n x n matrices are left out whatever their size
  double implicit_dt = 0;   // s: where the implicit fixed-step methods' sweeps start, if not where accuracy
                            // puts a first-order method's (time_scale / 256: the point of them is larger steps)
  // a scene of the user's (`stepwise study NAME --scene FILE`): how its model is made (model and params unused)
  std::function<std::unique_ptr<Model>()> factory = nullptr;
  // a PDE scene of the user's: its model on a grid of `points` an axis (0: the scene's) with stencils of `order`, and
  // whether its every axis is periodic (n points span it at h = 1/n of it, else 1/(n - 1)); null for any other scene
  std::function<std::unique_ptr<Model>(int points, int order)> on_grid = nullptr;
  bool periodic = false;
};

// the scene's model: the user's factory, or the built-in model with the scene's parameters
inline std::unique_ptr<Model> scene_model(const StudyScene& scene) { return scene.factory ? scene.factory() : make_model(scene.model, scene.params); }

// the study's scenes: the user's where `--scene` gave one, else the study's own
inline std::vector<StudyScene> scenes_or(const StudyContext& ctx, std::vector<StudyScene> own) { return ctx.scenes ? *ctx.scenes : own; }

// a scene without an exact solution is measured against gsl-rk8pd at this tolerance (atol 1e-3 of it): the
// cloth's errors flatten at 3e-13 there, the reference's own
inline constexpr double reference_rtol = 1e-13;
inline constexpr std::string_view reference_method = "gsl-rk8pd";

// the rendered frame's height in pixels (1280 x 720): half a pixel of it is the animation's error target
inline constexpr double frame_pixels = 720;
// the flag (1 m square, billowing out of its plane) is filmed in a 1.5 m frame
inline constexpr double flag_frame_extent = 1.5;
inline constexpr double verification_target = 1e-8;

inline std::vector<StudyScene> ode_scenes() {
  return {// the bob swings through 2 L sin(1 rad) = 1.7 m of a 1 m pendulum: a 2.5 m frame
          {"pendulum", "pendulum", {{"theta0", 1.0}}, 10.0, 0.25, 2.5},
          // the particle moves about 1 m in the unit flow over 1 s
          {"flow-particle", "flow-particle", {}, 1.0, 1.0, 2.0},
          // launched at (10, 10) m/s with drag 0.5/s: 12 m downrange and 4.5 m up in 2 s
          {"projectile", "projectile", {{"drag", 0.5}}, 2.0, 1.0, 12.0},
          // one particle of the particle system without repulsion: three damped oscillators, w = 2 rad/s; it
          // sags g / w^2 = 2.5 m under gravity from within a 2 m box
          {"particle-system", "particle-system", {{"count", 1}, {"repulsion", 0}}, 2.0, 0.5, 5.0},
          // the (1, 2) mode of a 17^2 height field against its exact semi-discrete solution: the seeds' scheme
          // beside the method of lines. The time scale is 16 times the scheme's stability limit (0.044 s), so
          // wave-fd starts at half its limit and rk4 and the Euler family start past theirs (shown diverged)
          // and halve into stability. The frame shows the 1 m pool.
          {"standing-wave", "standing-wave", {{"size", 17}, {"spacing", 1.0 / 16}, {"c", 1}, {"mu", 0.5}, {"mode_m", 1}, {"mode_n", 2}, {"amplitude", 1}}, 2.0,
           16 * wave_stable_dt({17, 1.0 / 16, 1, 0.5}), 1.0},
          // the Taylor-Green vortex on 16^2 points (512 unknowns) against its exact decay: mode 2 (k = 4 pi),
          // nu = 0.05, for 0.2 s, while its velocity falls by e^(-2 nu k^2 t) = e^(-3.2). Its time scale is that
          // decay's, 1 / (2 nu k^2) (only the one mode moves; the grid's highest kept mode, damped at nu 2 (10 pi)^2,
          // holds rk4 below 0.028 s, where the sweeps start past and halve into); the frame shows the unit square
          {"taylor-green-16", "taylor-green", {{"size", 16}, {"viscosity", 0.05}, {"mode", 2}}, 0.2,
           1 / (2 * 0.05 * std::pow(4 * std::numbers::pi, 2)), 1.0, false}};
}

// the work-precision sweeps' scenes: those above, and the hanging sheet at 6 x 6 (no exact solution: against
// the reference run) released flat for 0.5 s; its time scale 1/omega of its stiffest mode
inline std::vector<StudyScene> work_precision_scenes(bool quick) {
  auto scenes = ode_scenes();
  const Params sheet{{"rows", 6}, {"columns", 6}, {"width", 1}, {"height", 1}, {"mass", 0.4}, {"stiffness", 200}, {"shear_stiffness", 100},
                     {"bend_stiffness", 10}, {"damping", 0.05}, {"drag", 0.1}, {"pin_top_corners", 1}, {"pin_corners", 0}, {"wind_coefficient", 0}};
  const auto model = make_model("cloth", sheet);
  const double omega = stiffest_mode(*model, 0, model->initial_state()).omega;
  // the sheet falls for 0.5 s from its 1 m start: a 1.5 m frame. GSL's implicit steppers, with a dense
  // Jacobian by differences each step, take 3-4 s a point at rtol 1e-6 (204 unknowns): left out, cvode-bdf
  // on KLU, implicit-euler on CHOLMOD and Liu's method stand for the implicit methods
  scenes.push_back({"hanging-cloth-6x6", "cloth", sheet, 0.5, 1 / omega, 1.5, false, 0.05});
  // the double shear layer on 24^2 (1152 unknowns; against the reference run: the study is of the time
  // integrators, and the report's budget is minutes) for 0.25 s, while the layers begin to roll up; its fastest
  // time scale 1 / (A kmax) = 1 / (2 pi 8) s, advective. The frame shows the unit square
  // The fluid's two in the full report only: the quick report's budget is a minute, and their sweeps took a third
  // of it (the Taylor-Green vortex stays in the quick convergence study)
  if (quick) {
    std::erase_if(scenes, [](const StudyScene& s) { return s.model == "taylor-green"; });
  } else {
    scenes.push_back({"shear-layer-24", "shear-layer", {{"size", 24}}, 0.25, 1 / (2 * std::numbers::pi * 8), 1.0, false});
  }
  return scenes;
}

// methods whose dense n x n matrices exceed this (362 unknowns) are left out of a scene's sweeps: a dense
// LU of the standing wave's 578 unknowns (64 MFLOP) at every step of every point would take the report's
// whole budget, and cvode-bdf (KLU on the sparse Jacobian) is there to represent the implicit methods
inline constexpr double dense_matrix_budget = 1 << 20;

inline constexpr std::string_view dense_note =
    "Methods that would keep dense n x n matrices larger than 1 MiB (the standing wave's 578 unknowns: GSL's implicit steppers) are left "
    "out of a scene, and so is implicit-euler's full Newton beyond as many unknowns (on a sparse Jacobian a sparse LU at every "
    "iteration: 17 s of a quick report's sweeps on the standing wave); cvode-bdf, with KLU on the sparse Jacobian, stands for the implicit methods there. On the "
    "cloth, GSL's implicit steppers (a dense Jacobian by differences every step: 3-4 s a point at rtol 1e-6) are left out too; "
    "implicit-euler on CHOLMOD and fast-mass-spring join cvode-bdf there.\n\n";

// the constrained methods (xpbd, rattle, ida: a cloth's springs are compliant constraints too) are measured in the
// constraints study, at their own settings (substeps and iterations), not in these sweeps of steps and tolerances;
// a method with a twin (a GPU compute pass) gives its twin's numbers, measured once
// implicit Euler's full Newton factorises I - hJ at every iteration: on a sparse Jacobian (UMFPACK) its sweeps of the
// standing wave's 578 unknowns took 17 s of a quick report's work-precision, so (but for its mass-spring solver) it
// keeps the dense rule's reach in the sweeps, 362 unknowns, and a scene that keeps dense matrices out keeps it out
inline constexpr int newton_per_iteration_unknowns = 362;

inline bool in_sweep(const Method& method, const Model& model, bool dense) {
  const double bytes = dense_matrix_bytes(method, model);
  const bool newton_out = method.family == Family::implicit_euler && !model.as<MassSpringView>() && (!dense || model.size() > newton_per_iteration_unknowns);
  return method_applies(method, model) && bytes <= dense_matrix_budget && (dense || bytes == 0) && !newton_out &&
         method.needs.type != &typeid(DistanceConstraints) && method.twin.empty();
}

// the methods of a scene's sweeps, fixed-step ones only if asked
inline std::vector<const Method*> scene_methods(const StudyScene& scene, bool fixed_only) {
  const auto model = scene_model(scene);
  std::vector<const Method*> chosen;
  for (const auto& method : methods())
    if (in_sweep(method, *model, scene.dense) && (method.fixed_step() || !fixed_only)) chosen.push_back(&method);
  return chosen;
}

}  // namespace stepwise
