#include "method.hpp"

#include "newton_matrix.hpp"

#include "capabilities/contact_bodies.hpp"
#include "capabilities/distance_constraints.hpp"
#include "capabilities/mass_spring.hpp"

#include <fmt/format.h>

#include <fmt/ranges.h>

#include <charconv>
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

std::string MethodOption::type_text() const {
  switch (kind) {
    case Kind::whole: return "INT";
    case Kind::real: return "FLOAT";
    case Kind::choice: break;
  }
  return fmt::format("{}", fmt::join(choices, "|"));
}

std::string MethodOption::range_text() const {
  switch (kind) {
    case Kind::whole: return fmt::format("{}..{}", static_cast<long long>(min), static_cast<long long>(max));
    case Kind::real: return fmt::format("({}, {})", min, max);
    case Kind::choice: break;
  }
  return fmt::format("{}", fmt::join(choices, " or "));
}

std::string MethodOption::value_text(double value) const {
  if (kind == Kind::choice) {
    const auto at = static_cast<size_t>(value);
    return value >= 0 && at < choices.size() && double(at) == value ? std::string(choices[at]) : fmt::format("{}", value);
  }
  return fmt::format("{}", value);  // the shortest text that reads back as the value
}

std::string MethodOption::refusal(double value) const {
  switch (kind) {
    case Kind::whole:
      if (!(value >= min && value <= max && std::floor(value) == value)) return fmt::format("must be a whole number in {}", range_text());
      break;
    case Kind::real:
      if (!(value > min && value < max)) return fmt::format("must lie in {}", range_text());
      break;
    case Kind::choice:
      if (!(value >= 0 && value < double(choices.size()) && std::floor(value) == value)) return fmt::format("must be {}", range_text());
      break;
  }
  return {};
}

double MethodOption::parse(std::string_view text) const {
  if (kind == Kind::choice) {
    for (size_t i = 0; i < choices.size(); ++i)
      if (choices[i] == text) return double(i);
    throw BadMethod(fmt::format("must be {}", range_text()));
  }
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || text.empty())
    throw BadMethod(kind == Kind::whole ? fmt::format("not a number (a whole number in {})", range_text()) : fmt::format("not a number (a number in {})", range_text()));
  if (const std::string why = refusal(value); !why.empty()) throw BadMethod(why);
  return value;
}

const MethodOption* Method::option(std::string_view option_name) const {
  for (const auto& o : options)
    if (o.name == option_name) return &o;
  return nullptr;
}

double Method::setting(const StepControl& control, std::string_view option_name) const {
  const MethodOption* o = option(option_name);
  if (!o) throw std::logic_error(fmt::format("{} declares no option {}", name, option_name));
  const auto given = control.settings.find(option_name);
  return given != control.settings.end() ? given->second : o->fallback;
}

int Method::whole_setting(const StepControl& control, std::string_view option_name) const {
  return static_cast<int>(setting(control, option_name));
}

void MethodTable::add(Method method) {
  if (find(method.name)) throw std::logic_error(fmt::format("method '{}' registered twice", method.name));
  for (const auto& o : method.options) {
    if (!o.refusal(o.fallback).empty()) throw std::logic_error(fmt::format("method '{}': option {}'s default {} {}", method.name, o.name, o.fallback, o.refusal(o.fallback)));
    for (const auto& other : methods_)
      if (const MethodOption* same = other.option(o.name); same && (same->kind != o.kind || same->key() != o.key() || same->choices != o.choices))
        throw std::logic_error(fmt::format("method '{}': option {} is declared otherwise by {} (one --{} serves every method)", method.name, o.name, other.name, o.name));
  }
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

std::string options_text(const Method& method) {
  if (method.options.empty()) return fmt::format("{} has no options of its own", method.name);
  std::vector<std::string> names;
  for (const auto& o : method.options) names.push_back(fmt::format("--{}", o.name));
  return fmt::format("its own: {}", fmt::join(names, ", "));
}

void check_step_control(const Method& method, const StepControl& control) {
  if (control.dt && !method.fixed_step())
    throw BadMethod(fmt::format("{} is adaptive only: give --rtol/--atol, not --dt", method.name));
  if (!control.dt && !method.adaptive()) throw BadMethod(fmt::format("{} is a fixed-step method: give --dt", method.name));
  if (control.dt && !(std::isfinite(*control.dt) && *control.dt > 0))
    throw BadMethod(fmt::format("dt must be a positive finite number, got {}", *control.dt));
  if (!control.dt && !(control.rtol > 0 && control.atol > 0 && std::isfinite(control.rtol) && std::isfinite(control.atol)))
    throw BadMethod(fmt::format("rtol and atol must be positive finite numbers, got {} and {}", control.rtol, control.atol));
  for (const auto& [name, value] : control.settings) {
    const MethodOption* o = method.option(name);
    if (!o) throw BadMethod(fmt::format("--{}: {} takes no such option ({})", name, method.name, options_text(method)));
    if (const std::string why = o->refusal(value); !why.empty()) throw BadMethod(fmt::format("--{} {}: {}", name, o->value_text(value), why));
  }
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
