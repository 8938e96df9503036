#include "method.hpp"

#include "newton_matrix.hpp"

#include "capabilities/contact_bodies.hpp"
#include "capabilities/distance_constraints.hpp"
#include "capabilities/mass_spring.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace stepwise {

std::string_view to_string(Family family) {
  switch (family) {
    case Family::euler: return "euler";
    case Family::symplectic_euler: return "symplectic-euler";
    case Family::rk4: return "rk4";
    case Family::embedded_pairs: return "embedded-pairs";
    case Family::odeint: return "odeint";
    case Family::gsl: return "gsl";
    case Family::cvode: return "cvode";
    case Family::arkode: return "arkode";
    case Family::rosenbrock: return "rosenbrock";
    case Family::implicit_euler: return "implicit-euler";
    case Family::fast_mass_spring: return "fast-mass-spring";
    case Family::position_based: return "position-based";
    case Family::vertex_block_descent: return "vertex-block-descent";
    case Family::constrained: return "constrained";
    case Family::rigid_splitting: return "rigid-splitting";
    case Family::sequential_impulses: return "sequential-impulses";
    case Family::wave_fd: return "wave-fd";
    case Family::stable_fluids: return "stable-fluids";
    case Family::gpu: return "gpu";
  }
  return "unknown";
}

std::string_view to_string(Source source) {
  switch (source) {
    case Source::hand_written: return "hand-written";
    case Source::gsl: return "GSL odeiv2";
    case Source::cvode: return "SUNDIALS CVODE";
    case Source::arkode: return "SUNDIALS ARKODE";
    case Source::ida: return "SUNDIALS IDA";
    case Source::odeint: return "Boost.Odeint";
    case Source::opengl_shader: return "OpenGL shader";
  }
  return "unknown";
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
  // bodies in contact and a method that resolves contacts go together, both ways: such a system's f holds only
  // the smooth forces
  const bool resolves_contacts = method.needs.type == needs_contact_bodies.type;
  return method.needs.offered_by(system) && resolves_contacts == (system.as<ContactBodiesView>() != nullptr);
}

std::string method_requirement(const Method& method, const OdeSystem& system) {
  if (system.as<ContactBodiesView>() && method.needs.type != needs_contact_bodies.type)
    return fmt::format("{} has no contact response, and these bodies touch: they need a method that resolves contacts (sequential-impulses)", method.name);
  if (!method.needs.type) return {};
  return fmt::format("{} needs {}", method.name, method.needs.what);
}

void check_step_control(const Method& method, const StepControl& control) {
  if (control.dt && !method.fixed_step())
    throw BadMethod(fmt::format("{} is adaptive only: give --rtol/--atol, not --dt", method.name));
  if (!control.dt && !method.adaptive()) throw BadMethod(fmt::format("{} is a fixed-step method: give --dt", method.name));
  if (control.dt && !(std::isfinite(*control.dt) && *control.dt > 0))
    throw BadMethod(fmt::format("dt must be a positive finite number, got {}", *control.dt));
  if (!control.dt && !(control.rtol > 0 && control.atol > 0 && std::isfinite(control.rtol) && std::isfinite(control.atol)))
    throw BadMethod(fmt::format("rtol and atol must be positive finite numbers, got {} and {}", control.rtol, control.atol));
  if (!(control.substeps >= 1 && control.substeps <= max_substeps && control.iterations >= 1 && control.iterations <= max_substeps))
    throw BadMethod(fmt::format("substeps and iterations must be whole numbers in 1..{}, got {} and {}", max_substeps, control.substeps, control.iterations));
}

double dense_matrix_bytes(const Method& method, const OdeSystem& system) {
  switch (method.dense) {
    case DenseMatrices::none: return 0;
    case DenseMatrices::unless_sparse_jacobian:
      if (system.as<SparseJacobian>()) return 0;
      break;
    case DenseMatrices::unless_mass_spring_or_sparse:
      if (system.as<MassSpringView>() || (system.as<SparseJacobian>() && system.size() >= sparse_newton_from)) return 0;
      break;
    case DenseMatrices::always: break;
    case DenseMatrices::constrained_dae: break;
  }
  // the unknowns: the state, and for a DAE two multipliers a constraint
  const auto* constraints = method.dense == DenseMatrices::constrained_dae ? system.as<DistanceConstraints>() : nullptr;
  const double n = system.size() + (constraints ? 2.0 * double(constraints->constraints.size()) : 0.0);
  // the Jacobian, the Newton matrix and (GSL's implicit steppers, Bulirsch-Stoer) one more: peak resident size
  // measured on the water drop at 30 x 30 and 40 x 40 (1 800 and 3 200 unknowns) above the run's baseline,
  // 2.0-2.2 n^2 doubles for implicit-euler and 2.9-3.05 for gsl-bsimp; the larger rounded up is the rule
  return 3.1 * n * n * sizeof(double);
}

}  // namespace stepwise
