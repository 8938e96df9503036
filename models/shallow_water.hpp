// The shallow water equations on the height field's grid: the non-linear model beside the linear wave
// equation, to show at which amplitude the wave equation stops being enough (the water's second model).
//
// Water of rest depth H, surface eta(x, y, t) above rest, depth h = H + eta, depth-averaged velocity (u, w):
//
//   d eta/dt = -d(h u)/dx - d(h w)/dy
//   du/dt    = -g d eta/dx - (u du/dx + w du/dy) - mu u
//   dw/dt    = -g d eta/dy - (u dw/dx + w dw/dy) - mu w
//
// on an Arakawa C grid over the height field's points: eta at the points (i d, j d), eta = 0 on the
// boundary as there, u at the x-faces ((i + 1/2) d, j d) and w at the y-faces (i d, (j + 1/2) d) between
// interior rows; the depth on a face is the mean of its two points', the advection terms centred, the
// cross velocity averaged from the four faces around. Linearised (eta << H, u small) it is
// d2 eta/dt2 = g H Lap eta - mu d eta/dt with the same 5-point Laplacian as the height field: the wave
// equation with c^2 = g H, to which it tends as the amplitude goes to 0, its first departure being of
// order eta / H (the mass flux's eta u and the advection's u du/dx).
//
// The damping -mu u gives the wave equation's -mu d eta/dt exactly in the linear limit.
//
// state: eta on all size^2 points (m), then u and w each on size^2 slots (m/s), row-major as the height
// field (i along x); slots that are no face (u past the last column of faces, faces along the boundary
// rows) stay 0.
//
// Scene: shallow-water-drop (the water-drop's raised cosine, at rest).
#pragma once

#include <stepwise/models/model.hpp>

namespace stepwise {

std::span<const ParamSpec> shallow_water_params();
std::unique_ptr<Model> make_shallow_water(const Params& params);

}  // namespace stepwise
