// SUNDIALS CVODE behind the Integrator interface; SUNDIALS types stay in cvode_backend.cpp.
#pragma once

#include "integrator.hpp"

namespace stepwise {

// method is cvode-adams (fixed-point iteration) or cvode-bdf (Newton; dense LU, or KLU when the
// system has a sparse Jacobian); always adaptive to control.rtol/atol
std::unique_ptr<Integrator> make_cvode_integrator(std::string_view method, const StepControl& control);

}  // namespace stepwise
