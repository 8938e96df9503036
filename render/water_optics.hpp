// The optics of light through a water surface (seed: height-field water rendering, two-pass photon map):
// the surface's normals, Snell refraction and the Fresnel transmittance. The caustic shaders compute the
// same in GLSL; these are the CPU forms the photon tracer and the tests use.
#pragma once

#include <stepwise/models/shapes.hpp>

#include <Eigen/Dense>

#include <optional>
#include <vector>

namespace stepwise::render {

constexpr double water_index = 1.333;  // refractive index of water against air

// unit normals of the height field at its nodes, (-dz/dx, -dz/dy, 1) normalised, by central differences
// inside and one-sided differences on the edges; points^2 rows, row-major like z
Eigen::Matrix<double, Eigen::Dynamic, 3> height_field_normals(const Shapes::Water& water);

// the direction d (unit, d . n < 0) refracted through a surface of unit normal n from index 1 into index
// `index`: t = eta d + (eta cos_i - cos_t) n with eta = 1 / index (Snell's law in vector form)
Eigen::Vector3d refract(const Eigen::Vector3d& d, const Eigen::Vector3d& n, double index);

// the fraction of unpolarised light transmitted at incidence cos_i from index 1 into `index`: 1 - (Rs + Rp) / 2
// with Rs = ((cos_i - m cos_t) / (cos_i + m cos_t))^2, Rp = ((cos_t - m cos_i) / (cos_t + m cos_i))^2 (Fresnel)
double fresnel_transmittance(double cos_i, double index);

// fresnel_transmittance as GLSL (float fresnel_transmittance(float cos_i, float index)), for the shaders
extern const char* const glsl_fresnel;

}  // namespace stepwise::render
