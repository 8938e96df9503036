#include "method.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace stepwise {

bool offers(const OdeSystem& system, Capability capability) {
  switch (capability) {
    case Capability::none: return true;
    case Capability::second_order: return system.second_order().has_value();
    case Capability::wave_grid: return system.wave_grid().has_value();
    case Capability::free_rigid_body: return system.free_rigid_body().has_value();
    case Capability::contact_bodies: return system.contact_bodies().has_value();
    case Capability::mass_spring: return system.mass_spring() != nullptr;
    case Capability::cloth_grid: return system.cloth_grid() != nullptr;
  }
  return false;
}

void MethodTable::add(Method method) {
  if (find(method.name)) throw std::logic_error(fmt::format("method '{}' registered twice", method.name));
  methods_.push_back(std::move(method));
}

const Method* MethodTable::find(std::string_view name) const {
  for (const auto& m : methods_)
    if (m.name == name) return &m;
  return nullptr;
}

bool method_applies(const Method& method, const OdeSystem& system) {
  // bodies in contact and a method that resolves contacts go together, both ways
  const bool resolves_contacts = method.needs == Capability::contact_bodies;
  return offers(system, method.needs) && resolves_contacts == system.contact_bodies().has_value();
}

std::string method_requirement(const Method& method, const OdeSystem& system) {
  if (system.contact_bodies() && method.needs != Capability::contact_bodies)
    return fmt::format("{} has no contact response, and these bodies touch: they need a method that resolves contacts (sequential-impulses)", method.name);
  switch (method.needs) {
    case Capability::none: return {};
    case Capability::contact_bodies: return fmt::format("{} needs rigid bodies in contact (a contact scene)", method.name);
    case Capability::wave_grid: return fmt::format("{} needs a wave equation on a grid (a water scene)", method.name);
    case Capability::free_rigid_body:
      return fmt::format("{} needs a torque-free rigid body (a rigid-body scene without drag or torque)", method.name);
    case Capability::cloth_grid: return fmt::format("{} needs a cloth on a grid (a cloth scene)", method.name);
    case Capability::mass_spring: return fmt::format("{} needs a mass-spring system (a cloth or chain scene)", method.name);
    case Capability::second_order: return fmt::format("{} needs a second-order model y = (x, v)", method.name);
  }
  return {};
}

void check_step_control(const Method& method, const StepControl& control) {
  if (control.dt && !method.fixed_step())
    throw BadMethod(fmt::format("{} is adaptive only: give --rtol/--atol, not --dt", method.name));
  if (!control.dt && !method.adaptive()) throw BadMethod(fmt::format("{} is a fixed-step method: give --dt", method.name));
  if (control.dt && !(std::isfinite(*control.dt) && *control.dt > 0))
    throw BadMethod(fmt::format("dt must be a positive finite number, got {}", *control.dt));
  if (!control.dt && !(control.rtol > 0 && control.atol > 0 && std::isfinite(control.rtol) && std::isfinite(control.atol)))
    throw BadMethod(fmt::format("rtol and atol must be positive finite numbers, got {} and {}", control.rtol, control.atol));
}

double dense_matrix_bytes(const Method& method, const OdeSystem& system) {
  switch (method.dense) {
    case DenseMatrices::none: return 0;
    case DenseMatrices::unless_sparse_jacobian:
      if (system.has_sparse_jacobian()) return 0;
      break;
    case DenseMatrices::unless_mass_spring:
      if (system.mass_spring()) return 0;
      break;
    case DenseMatrices::always: break;
  }
  const double n = system.size();
  // the Jacobian and the Newton matrix (GSL's implicit steppers and Bulirsch-Stoer keep a few more)
  return 2 * n * n * sizeof(double);
}

}  // namespace stepwise
