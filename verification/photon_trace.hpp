// An independent check of the GPU photon map (render/caustics.hpp): rays of a unit-irradiance beam traced
// one by one through the same water surface and binned on the pool floor (Monte Carlo).
//
// The surface is the photon map's: the height field's triangles, two per cell, with the vertex normals
// interpolated across each (render/water_optics.hpp). A ray enters at a uniformly drawn point (x, y) of the
// square, carries the beam's power through the horizontal element there, E0 dA (n_f . l) / n_f,z (n_f the
// face normal), times the Fresnel transmittance at n_f . l, and is refracted by the interpolated normal onto
// z = -depth. The photon map instead projects whole triangles by their vertex rays; the two differ by the
// map's rasterisation and the non-linearity of the ray map inside a triangle, both small on a fine grid.
#pragma once

#include <stepwise/models/shapes.hpp>

#include <Eigen/Dense>

#include <cstdint>
#include <vector>

namespace stepwise {

struct PhotonTrace {
  int bins = 0;                    // per side, over the floor [0, side]^2
  std::vector<double> irradiance;  // bins^2, row i at y = (i + 1/2) side / bins (per unit beam irradiance)
  std::vector<double> sigma;       // its Monte Carlo standard error, per bin
};

PhotonTrace trace_photons(const Shapes::Water& water, const Eigen::Vector3d& light, double depth, int bins, long rays,
                          std::uint64_t seed);

}  // namespace stepwise
