// Caustics under a height-field water surface (seed: two-pass photon map). Pass 1, here: each surface
// triangle's vertices are refracted along the light (Snell, n = 1.333, vertex normals of the height field)
// onto the pool floor z = -depth, and the triangle's transmitted power E0 A cos(theta) T(theta) (A its area,
// theta the incidence on its face, T the Fresnel transmittance) is spread over the projected triangle:
// irradiance power / projected area, summed by additive blending into a float (RGBA32F) map, so triangles
// that overlap at a fold add up. Pass 2 (render/renderer.cpp) lights the floor with the map.
#pragma once

#include "gl/context.hpp"
#include <stepwise/models/shapes.hpp>

#include <Eigen/Dense>

#include <memory>
#include <vector>

namespace stepwise::render {

class PhotonMap {
 public:
  // resolution x resolution texels over the floor [0, side]^2; GlError if the program or target fails
  PhotonMap(const gl::Context& context, int resolution);
  ~PhotonMap();
  PhotonMap(const PhotonMap&) = delete;
  PhotonMap& operator=(const PhotonMap&) = delete;

  // deposits the photons of a beam of unit irradiance (normal to the beam) from direction `light` (unit,
  // towards the light) through `water` onto the floor at z = -depth; the map stays in the texture
  void build(const Shapes::Water& water, const Eigen::Vector3d& light, double depth);
  // the map's irradiances (per unit floor area, per unit beam irradiance), row i at y = (i + 1/2) side / resolution
  std::vector<float> read() const;
  unsigned texture() const { return texture_; }
  // the last build's surface: two triangles per cell, each vertex its position and normal (6 floats), the
  // mesh the water surface is drawn with
  const std::vector<float>& surface() const { return vertices_; }
  int resolution() const { return resolution_; }

 private:
  const gl::Context& context_;
  const gl::Gl& gl_;
  int resolution_;
  std::vector<float> vertices_;
  unsigned program_ = 0, texture_ = 0, framebuffer_ = 0, vertex_array_ = 0, buffer_ = 0;
};

}  // namespace stepwise::render
