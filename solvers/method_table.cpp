#include "method_table.hpp"

#include <fmt/format.h>

namespace stepwise {

// each family's file registers its own methods (solvers/methods/, solvers/gpu/); a new family adds its file
// and one line here, where the lines' order is the table's
void register_euler_methods(MethodTable& table);
void register_symplectic_euler_methods(MethodTable& table);
void register_rk4_methods(MethodTable& table);
void register_embedded_pair_methods(MethodTable& table);
void register_rosenbrock_methods(MethodTable& table);
void register_implicit_euler_methods(MethodTable& table);
void register_cvode_methods(MethodTable& table);
void register_arkode_methods(MethodTable& table);
void register_gsl_methods(MethodTable& table);
void register_odeint_methods(MethodTable& table);
void register_wave_fd_methods(MethodTable& table);
void register_rigid_splitting_methods(MethodTable& table);
void register_sequential_impulses_methods(MethodTable& table);
void register_fast_mass_spring_methods(MethodTable& table);
void register_stable_fluids_methods(MethodTable& table);
void register_position_based_methods(MethodTable& table);
void register_vbd_methods(MethodTable& table);
void register_rattle_methods(MethodTable& table);
void register_ida_methods(MethodTable& table);
namespace gpu {
void register_gpu_methods(MethodTable& table);
}

namespace {

const MethodTable& table() {
  static const MethodTable made = [] {
    MethodTable t;
    register_euler_methods(t);
    register_symplectic_euler_methods(t);
    register_rk4_methods(t);
    register_embedded_pair_methods(t);
    register_implicit_euler_methods(t);
    register_rosenbrock_methods(t);
    register_cvode_methods(t);
    register_arkode_methods(t);
    register_gsl_methods(t);
    register_odeint_methods(t);
    register_wave_fd_methods(t);
    gpu::register_gpu_methods(t);
    register_rigid_splitting_methods(t);
    register_sequential_impulses_methods(t);
    register_fast_mass_spring_methods(t);
    register_stable_fluids_methods(t);
    register_position_based_methods(t);
    register_vbd_methods(t);
    register_rattle_methods(t);
    register_ida_methods(t);
    return t;
  }();
  return made;
}

}  // namespace

std::span<const Method> methods() { return table().all(); }

const Method* find_method(std::string_view name) { return table().find(name); }

std::vector<const Method*> methods_where(const std::function<bool(const Method&)>& keep) {
  std::vector<const Method*> kept;
  for (const Method& m : table().all())
    if (keep(m)) kept.push_back(&m);
  return kept;
}

std::unique_ptr<Integrator> make_integrator(std::string_view method, const StepControl& control) {
  const Method* m = find_method(method);
  if (!m) throw BadMethod(fmt::format("unknown method '{}' (see `stepwise methods`)", method));
  check_step_control(*m, control);
  return m->make(*m, control);
}

}  // namespace stepwise
