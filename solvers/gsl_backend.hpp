// GSL odeiv2 behind the Integrator interface; GSL's types stay in gsl_backend.cpp.
#pragma once

#include "integrator.hpp"

namespace stepwise {

// method is one of gsl-rk2 ... gsl-msbdf; fixed step when control.dt is set, else adaptive to rtol/atol
std::unique_ptr<Integrator> make_gsl_integrator(std::string_view method, const StepControl& control);

}  // namespace stepwise
