#include "integrator.hpp"

#include "cvode_backend.hpp"
#include "fixed_step.hpp"
#include "gsl_backend.hpp"

#include <fmt/format.h>

#include <unistd.h>

#include <array>
#include <cmath>
#include <map>

namespace stepwise {

std::string_view to_string(Status status) {
  switch (status) {
    case Status::ok: return "ok";
    case Status::diverged: return "diverged";
    case Status::failed: return "failed";
  }
  return "failed";
}

namespace {

// DESIGN.md's method table. GSL's orders as measured by the convergence tests: its embedded pairs advance
// with the higher-order solution (rk2 is a 2(3) pair of order 3, rk8pd an 8(9) pair of order 9)
constexpr std::array method_table{
    MethodInfo{"euler", "explicit, fixed step", "1", "hand-written", 1, 1, true, false, false},
    MethodInfo{"symplectic-euler", "semi-implicit, fixed step", "1", "hand-written", 1, 1, true, false, true},
    MethodInfo{"rk4", "explicit, fixed step", "4", "hand-written", 4, 4, true, false, false},
    MethodInfo{"implicit-euler", "implicit, fixed step; Newton + dense LU, or for mass-spring systems Baraff-Witkin's linearised step "
               "on CHOLMOD (a kept factor preconditioning CG)", "1", "hand-written", 1, 1, true, false, false, true},
    MethodInfo{"implicit-euler-newton", "implicit, fixed step, Newton to convergence (CHOLMOD for mass-spring systems, else dense LU)",
               "1", "hand-written", 1, 1, true, false, false, true},
    MethodInfo{"cvode-adams", "adaptive, variable order Adams-Moulton, fixed-point iteration", "1-12", "SUNDIALS CVODE", 1, 12, false, true, false},
    MethodInfo{"cvode-bdf", "adaptive, variable order BDF, Newton + dense LU or KLU", "1-5", "SUNDIALS CVODE", 1, 5, false, true, false, true, true},
    MethodInfo{"gsl-rk2", "explicit embedded Runge-Kutta (2,3), advances with the third-order solution", "3", "GSL odeiv2", 3, 3, true, true, false},
    MethodInfo{"gsl-rk4", "explicit classical Runge-Kutta, error by step doubling", "4", "GSL odeiv2", 4, 4, true, true, false},
    MethodInfo{"gsl-rkf45", "explicit embedded Runge-Kutta-Fehlberg (4,5)", "5", "GSL odeiv2", 5, 5, true, true, false},
    MethodInfo{"gsl-rkck", "explicit embedded Runge-Kutta Cash-Karp (4,5)", "5", "GSL odeiv2", 5, 5, true, true, false},
    MethodInfo{"gsl-rk8pd", "explicit embedded Runge-Kutta Prince-Dormand (8,9), advances with the ninth-order solution", "9", "GSL odeiv2", 9, 9, true, true, false},
    MethodInfo{"gsl-rk1imp", "implicit Gaussian first order Runge-Kutta (backward Euler)", "1", "GSL odeiv2", 1, 1, true, true, false, true},
    MethodInfo{"gsl-rk2imp", "implicit Gaussian second order Runge-Kutta (midpoint)", "2", "GSL odeiv2", 2, 2, true, true, false, true},
    MethodInfo{"gsl-rk4imp", "implicit Gaussian fourth order Runge-Kutta", "4", "GSL odeiv2", 4, 4, true, true, false, true},
    MethodInfo{"gsl-bsimp", "implicit Bulirsch-Stoer (Bader-Deuflhard)", "variable", "GSL odeiv2", 1, 12, true, true, false, true},
    MethodInfo{"gsl-msadams", "variable order Adams, functional iteration", "1-12", "GSL odeiv2", 1, 12, true, true, false},
    MethodInfo{"gsl-msbdf", "variable order BDF, Newton iteration", "1-5", "GSL odeiv2", 1, 5, true, true, false, true},
    MethodInfo{"wave-fd", "explicit three-level finite differences for the damped wave equation (the seeds' scheme), fixed step",
               "2", "hand-written", 2, 2, true, false, false, false, false, true},
    MethodInfo{"gpu-wave", "the seeds' three-level scheme as a fragment-shader pass on float32 textures (OpenGL: llvmpipe, or a GPU "
               "through EGL), fixed step", "2", "OpenGL shader", 2, 2, true, false, false, false, false, true},
    MethodInfo{"gpu-symplectic-euler", "the second seed's scheme, symplectic Euler with the damping explicit, as a fragment-shader pass on "
               "float32 textures (OpenGL), fixed step", "1", "OpenGL shader", 1, 1, true, false, false, false, false, true},
    MethodInfo{"gpu-cloth", "the explicit mass-spring cloth (twelve springs a node, pins, gravity, wind, pick force, sphere and ground) "
               "as symplectic Euler in a fragment-shader pass on float32 textures (OpenGL), fixed step", "1", "OpenGL shader", 1, 1, true, false,
               false, false, false, false, false, false, false, true},
    MethodInfo{"rigid-splitting", "the free rigid body split into exact rotations about its principal axes, Strang-composed (symplectic, fixed step)",
               "2", "hand-written", 2, 2, true, false, false, false, false, false, true},
    MethodInfo{"sequential-impulses", "rigid bodies in contact: kick, contact impulses by projected Gauss-Seidel (restitution, Coulomb "
               "friction), drift (velocity-level time stepping, fixed step)", "1", "hand-written", 1, 1, true, false, false, false, false,
               false, false, true},
    MethodInfo{"fast-mass-spring", "mass-spring systems: prefactored local/global implicit Euler of the springs (Liu et al. 2013), "
               "other forces explicit, fixed step", "1", "hand-written", 1, 1, true, false, false, false, false, false, false, false, true},
};

}  // namespace

std::span<const MethodInfo> methods() { return method_table; }

const MethodInfo* find_method(std::string_view name) {
  for (const auto& m : method_table)
    if (m.name == name) return &m;
  return nullptr;
}

bool method_applies(const MethodInfo& method, const OdeSystem& system) {
  if (method.needs_second_order && !system.second_order()) return false;
  if (method.needs_wave_grid && !system.wave_grid()) return false;
  if (method.needs_free_rigid_body && !system.free_rigid_body()) return false;
  if (method.resolves_contacts != system.contact_bodies().has_value()) return false;
  if (method.needs_mass_spring && !system.mass_spring()) return false;
  if (method.needs_cloth_grid && !system.cloth_grid()) return false;
  return true;
}

std::string method_requirement(const MethodInfo& method, const OdeSystem& system) {
  if (system.contact_bodies() && !method.resolves_contacts)
    return fmt::format("{} has no contact response, and these bodies touch: they need a method that resolves contacts (sequential-impulses)", method.name);
  if (method.resolves_contacts) return fmt::format("{} needs rigid bodies in contact (a contact scene)", method.name);
  if (method.needs_wave_grid) return fmt::format("{} needs a wave equation on a grid (a water scene)", method.name);
  if (method.needs_free_rigid_body)
    return fmt::format("{} needs a torque-free rigid body (a rigid-body scene without drag or torque)", method.name);
  if (method.needs_cloth_grid) return fmt::format("{} needs a cloth on a grid (a cloth scene)", method.name);
  if (method.needs_mass_spring) return fmt::format("{} needs a mass-spring system (a cloth or chain scene)", method.name);
  if (method.needs_second_order) return fmt::format("{} needs a second-order model y = (x, v)", method.name);
  return {};
}

namespace {

std::map<std::string, FixedStepperFactory, std::less<>>& registered_steppers() {
  static std::map<std::string, FixedStepperFactory, std::less<>> steppers;
  return steppers;
}

}  // namespace

void register_stepper(std::string_view method, FixedStepperFactory factory) { registered_steppers()[std::string(method)] = std::move(factory); }

std::unique_ptr<Integrator> make_integrator(std::string_view method, const StepControl& control) {
  const MethodInfo* info = find_method(method);
  if (!info) throw BadMethod(fmt::format("unknown method '{}' (see `stepwise methods`)", method));
  if (control.dt && !info->fixed_step)
    throw BadMethod(fmt::format("{} is adaptive only: give --rtol/--atol, not --dt", method));
  if (!control.dt && !info->adaptive) throw BadMethod(fmt::format("{} is a fixed-step method: give --dt", method));
  if (control.dt && !(std::isfinite(*control.dt) && *control.dt > 0))
    throw BadMethod(fmt::format("dt must be a positive finite number, got {}", *control.dt));
  if (!control.dt && !(control.rtol > 0 && control.atol > 0 && std::isfinite(control.rtol) && std::isfinite(control.atol)))
    throw BadMethod(fmt::format("rtol and atol must be positive finite numbers, got {} and {}", control.rtol, control.atol));

  const std::string name(method);
  if (method == "euler") return std::make_unique<FixedStepIntegrator>(name, control, make_euler);
  if (method == "symplectic-euler") return std::make_unique<FixedStepIntegrator>(name, control, make_symplectic_euler);
  if (method == "rk4") return std::make_unique<FixedStepIntegrator>(name, control, make_rk4);
  if (method == "implicit-euler") return std::make_unique<FixedStepIntegrator>(name, control, make_implicit_euler);
  if (method == "implicit-euler-newton") return std::make_unique<FixedStepIntegrator>(name, control, make_implicit_euler_newton);
  if (method == "fast-mass-spring") return std::make_unique<FixedStepIntegrator>(name, control, make_fast_mass_spring);
  if (method == "wave-fd") return std::make_unique<FixedStepIntegrator>(name, control, make_wave_fd);
  if (method == "rigid-splitting") return std::make_unique<FixedStepIntegrator>(name, control, make_rigid_splitting);
  if (method == "sequential-impulses") return std::make_unique<FixedStepIntegrator>(name, control, make_contact_stepping);
  if (const auto it = registered_steppers().find(method); it != registered_steppers().end())
    return std::make_unique<FixedStepIntegrator>(name, control, it->second);
  if (info->source == "OpenGL shader") throw BadMethod(fmt::format("{} runs on a GL device, and this program was built without one", method));
  if (info->source == "SUNDIALS CVODE") return make_cvode_integrator(method, control);
  return make_gsl_integrator(method, control);
}

double physical_memory_bytes() {
  return static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
}

double dense_matrix_bytes(const MethodInfo& method, const OdeSystem& system) {
  if (!method.dense_matrix || (method.sparse_newton && system.has_sparse_jacobian())) return 0;
  // the hand-written backward Euler solves a mass-spring system on CHOLMOD
  if (method.source == "hand-written" && system.mass_spring()) return 0;
  const double n = system.size();
  // the Jacobian and the Newton matrix (GSL's implicit steppers and Bulirsch-Stoer keep a few more)
  return 2 * n * n * sizeof(double);
}

}  // namespace stepwise
