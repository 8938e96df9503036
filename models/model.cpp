#include "model.hpp"

#include "bouncing_ball.hpp"
#include "flow_particle.hpp"
#include "fluid.hpp"
#include "cloth.hpp"
#include "hanging_chain.hpp"
#include "height_field.hpp"
#include "particle_mesh.hpp"
#include "particle_system.hpp"
#include "particles_in_box.hpp"
#include "pendulum.hpp"
#include "pendulum_cartesian.hpp"
#include "chain.hpp"
#include "projectile.hpp"
#include "rigid_body.hpp"
#include "rigid_contact.hpp"
#include "shallow_water.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>

namespace stepwise {

Eigen::VectorXd Model::exact(double) const {
  throw std::logic_error(fmt::format("model {} has no exact solution for these parameters", name()));
}

namespace {

const std::array model_table{
    ModelInfo{"pendulum", "nonlinear pendulum theta'' + (g/L) sin theta = 0; exact by Jacobi elliptic functions",
              pendulum_params(), [](const Params& p) { return make_pendulum(p, false); }},
    ModelInfo{"pendulum-small-angle", "linearised pendulum theta'' + (g/L) theta = 0 (sin theta ~ theta)",
              pendulum_params(), [](const Params& p) { return make_pendulum(p, true); }},
    ModelInfo{"pendulum-cartesian", "the pendulum as a point mass in the plane held by |x| = L (a distance constraint, compliance alpha); exact for alpha = 0",
              pendulum_cartesian_params(), [](const Params& p) { return make_pendulum_cartesian(p); }},
    ModelInfo{"chain", "an inextensible chain of N rigid links pinned at one end (distance constraints), released from the horizontal",
              chain_params(), [](const Params& p) { return make_chain(p); }, nullptr, nullptr, chain_columns},
    ModelInfo{"flow-particle", "particle carried by the velocity field (x, sin y); exact solution",
              flow_particle_params(), [](const Params& p) { return make_flow_particle(p); }},
    ModelInfo{"flow-particle-3d", "particle carried by the velocity field (x, y, sin x); exact solution via Si",
              flow_particle_3d_params(), [](const Params& p) { return make_flow_particle_3d(p); }},
    ModelInfo{"projectile", "particle under gravity with optional linear drag; exact solution",
              projectile_params(), [](const Params& p) { return make_projectile(p); }},
    ModelInfo{"bouncing-ball", "ball dropped on the ground plane with restitution; exact impact times and apex heights",
              bouncing_ball_params(), [](const Params& p) { return make_bouncing_ball(p); }},
    ModelInfo{"particles-in-box", "N particles under gravity bouncing off the six walls of a box; seeded, reproducible",
              particles_in_box_params(), [](const Params& p) { return make_particles_in_box(p); }},
    ModelInfo{"particle-system", "many particles in a trap with gravity and drag, optional short-range repulsion via a cell list",
              particle_system_params(), [](const Params& p) { return make_particle_system(p); }},
    ModelInfo{"particle-mesh", "particles falling on a convex triangle-mesh obstacle ([mesh]) and a ground plane of any normal",
              particle_mesh_params(), [](const Params& p) { return make_particle_mesh(p, default_obstacle()); },
              [](const Params& p, const TriangleMesh& mesh) { return make_particle_mesh(p, mesh); }},
    ModelInfo{"water-drop", "height-field water: a drop starts a circular wave (damped wave equation on a grid)",
              water_drop_params(), [](const Params& p) { return make_water_drop(p); }},
    ModelInfo{"standing-wave", "height-field water in one mode sin(m pi x/L) sin(n pi y/L); exact solution",
              standing_wave_params(), [](const Params& p) { return make_standing_wave(p); }},
    ModelInfo{"pool", "height-field water with drops falling at seeded random places and times (events)",
              pool_params(), [](const Params& p) { return make_pool(p); }},
    ModelInfo{"shallow-water", "non-linear shallow water equations on the height field's grid (C grid), a drop at rest; tends to "
              "the wave equation with c^2 = g H as the drop's height goes to 0", shallow_water_params(), [](const Params& p) { return make_shallow_water(p); }},
    ModelInfo{"taylor-green", "incompressible fluid (periodic, pseudo-spectral): the Taylor-Green vortex, decaying exactly",
              taylor_green_params(), [](const Params& p) { return make_taylor_green(p); }},
    ModelInfo{"shear-wave", "incompressible fluid (periodic, pseudo-spectral): a sine shear flow, decaying exactly",
              shear_wave_params(), [](const Params& p) { return make_shear_wave(p); }},
    ModelInfo{"shear-layer", "incompressible fluid (periodic, pseudo-spectral): Brown & Minion's double shear layer rolling up",
              shear_layer_params(), [](const Params& p) { return make_shear_layer(p); }},
    ModelInfo{"smoke", "incompressible fluid (periodic, pseudo-spectral) with a buoyant density fed by a source: a rising plume",
              smoke_params(), [](const Params& p) { return make_smoke(p); }},
    ModelInfo{"rigid-body", "one rigid body: Euler's equations, unit quaternion, gravity, drag, a force at a point",
              rigid_body_params(), [](const Params& p) { return make_rigid_body(p); },
              [](const Params& p, const TriangleMesh& mesh) { return make_rigid_body(p, mesh); }},
    ModelInfo{"hanging-chain", "N masses on Voigt springs hanging from a pin, gravity along -y; its static equilibrium is exact",
              hanging_chain_params(), [](const Params& p) { return make_hanging_chain(p); }, nullptr, nullptr,
              hanging_chain_columns},
    ModelInfo{"cloth", "a mass-spring cloth: structural, shear and bend Voigt springs, pins, gravity, wind through the normals, a "
              "picked node, a sphere and the ground", cloth_params(), [](const Params& p) { return make_cloth(p); }, nullptr,
              [](const Params& p, std::span<const GridNode> pins) { return make_cloth(p, pins); }},
    ModelInfo{"dropped-body", "a box (or the scene's convex [mesh]) dropped with a spin on the ground: contacts, restitution, friction",
              dropped_body_params(), [](const Params& p) { return make_dropped_body(p, nullptr); },
              [](const Params& p, const TriangleMesh& mesh) { return make_dropped_body(p, &mesh); }},
    ModelInfo{"box-stack", "a wall of boxes on the ground hit by a projectile (seeds: collapse in angry birds); deterministic",
              box_stack_params(), [](const Params& p) { return make_box_stack(p); }},
};

}  // namespace

std::span<const ModelInfo> models() { return model_table; }

const ModelInfo* find_model(std::string_view name) {
  for (const auto& m : model_table)
    if (m.name == name) return &m;
  return nullptr;
}

Params resolve_params(const ModelInfo& model, const Params& values) {
  Params resolved;
  for (const auto& spec : model.params) resolved[std::string(spec.key)] = spec.default_value;
  for (const auto& [key, value] : values) {
    const auto spec = std::find_if(model.params.begin(), model.params.end(), [&key = key](const ParamSpec& s) { return s.key == key; });
    if (spec == model.params.end()) {
      std::string known;
      for (const auto& s : model.params) known += (known.empty() ? "" : ", ") + std::string(s.key);
      throw BadParameter(key, fmt::format("unknown parameter '{}' of model {} (known: {})", key, model.name, known));
    }
    if (!std::isfinite(value)) throw BadParameter(key, fmt::format("parameter '{}' must be a finite number, got {}", key, value));
    if (spec->bound == Bound::positive && !(value > 0))
      throw BadParameter(key, fmt::format("parameter '{}' must be positive, got {}", key, value));
    if (spec->bound == Bound::nonnegative && !(value >= 0))
      throw BadParameter(key, fmt::format("parameter '{}' must be non-negative, got {}", key, value));
    if (spec->bound == Bound::unit_interval && !(value >= 0 && value <= 1))
      throw BadParameter(key, fmt::format("parameter '{}' must lie in [0, 1], got {}", key, value));
    if (spec->bound == Bound::flag && value != 0 && value != 1)
      throw BadParameter(key, fmt::format("parameter '{}' must be 0 or 1, got {}", key, value));
    resolved[key] = value;
  }
  return resolved;
}

std::unique_ptr<Model> make_model(std::string_view name, const Params& values) {
  const ModelInfo* info = find_model(name);
  if (!info) throw BadParameter("model", fmt::format("unknown model '{}'", name));
  return info->make(resolve_params(*info, values));
}

}  // namespace stepwise
