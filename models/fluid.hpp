// Incompressible fluid (the first seed's "Navier-Stokes for incompressible flows"; the second seed's smoke):
//
//   u' + (u . grad) u = -grad p + nu Lap u + b (rho - mean rho) e_y,   div u = 0,
//   rho' + u . grad rho = kappa Lap rho + s(x),
//
// on the periodic square [0, L)^2, n x n points (periodic_fft.hpp's layout), velocity u = (u, v) (m/s) and
// a passive density rho (smoke) that lifts the flow where it is above its mean (Boussinesq buoyancy b).
//
// Semi-discretised by the pseudo-spectral method of lines: derivatives in Fourier space, products on the
// grid, the 2/3 rule against aliasing and the Leray projection P for the pressure, so that
//
//   du/dt = P[ -(u . grad) u + b (rho - mean rho) e_y ] + nu Lap u,   drho/dt = -u . grad rho + kappa Lap rho + s,
//
// is an ordinary system every generic method integrates (and `stable-fluids` steps through fluid_grid).
// f is divergence-free and band-limited, so a divergence-free band-limited start stays so to round-off.
//
// Exact flows (the semi-discrete system's too: their modes are kept, their products are pure gradients):
//   taylor-green:  u = A sin(kx) cos(ky), v = -A cos(kx) sin(ky), k = 2 pi m / L: velocity x e^(-2 nu k^2 t)
//   shear-wave:    u = A sin(k y), v = 0: velocity x e^(-nu k^2 t)
// shear-layer: Brown & Minion's double shear layer, u = tanh(w (y - L/4)) below L/2, tanh(w (3L/4 - y))
// above, v = d sin(2 pi (x/L + 1/4)) (no exact solution). smoke: at rest, a Gaussian source of density
// near the bottom, rising.
//
// state: u, v, rho on all n^2 points; too large to write whole: trajectory.csv and final_state carry
// kinetic_energy (1/2 integral |u|^2 dA), enstrophy (1/2 integral w^2 dA, w = v_x - u_y), max_divergence
// (max |div u| on the grid, spectral derivative) and density_total (integral rho dA).
#pragma once

#include <stepwise/models/model.hpp>

namespace stepwise {

std::span<const ParamSpec> taylor_green_params();
std::span<const ParamSpec> shear_wave_params();
std::span<const ParamSpec> shear_layer_params();
std::span<const ParamSpec> smoke_params();
std::unique_ptr<Model> make_taylor_green(const Params& params);
std::unique_ptr<Model> make_shear_wave(const Params& params);
std::unique_ptr<Model> make_shear_layer(const Params& params);
std::unique_ptr<Model> make_smoke(const Params& params);

}  // namespace stepwise
