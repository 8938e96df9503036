// A particle carried by a velocity field: dp/dt = g(p, t) (seeds: "particle in a velocity field").
//
// 2-D, the seeds' field g = (x, sin y), p0 = (x0, y0), usually (1, 1) to T = 1:
//   x(t) = x0 e^t
//   dy/dt = sin y  =>  tan(y/2) = tan(y0/2) e^t  =>  y(t) = 2 atan(tan(y0/2) e^t)   (y0 in (-pi, pi), shifted by 2 pi n otherwise)
// 3-D, the seeds' field g = (x, y, sin x):
//   x = x0 e^t, y = y0 e^t, dz/dt = sin(x0 e^t)  =>  z(t) = z0 + Si(x0 e^t) - Si(x0)   (u = x0 e^s, ds = du/u)
// Units: positions in m, time in s (the field is in 1/s). No invariant: the field is not a force.
#pragma once

#include <stepwise/models/model.hpp>

namespace stepwise {

std::span<const ParamSpec> flow_particle_params();
std::span<const ParamSpec> flow_particle_3d_params();
std::unique_ptr<Model> make_flow_particle(const Params& params);
std::unique_ptr<Model> make_flow_particle_3d(const Params& params);

}  // namespace stepwise
