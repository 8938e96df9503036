// Draws a model's shapes (models/shapes.hpp) into an offscreen frame: lit balls (instanced), bodies (flat
// shaded), sheets (smooth, two-sided with a second colour behind), rods and trails as tubes, the ground
// (a checkered plane, or its line in a planar scene) and the container's edges; water in its pool with
// refraction, Fresnel reflection and caustics from a photon map (render/caustics.hpp).
#pragma once

#include <stepwise/render/camera.hpp>
#include "gl/context.hpp"
#include <stepwise/render/image.hpp>

#include <memory>
#include <span>
#include <vector>

namespace stepwise::render {

// how every frame of one animation is seen
struct View {
  Camera camera;
  Eigen::Vector3d light;        // unit, towards the light
  double point_radius = 0;      // drawn radius of point particles (m)
  double pool_depth = 0;        // water: floor at z = -pool_depth (m)
  int photon_resolution = 512;  // water: photon map texels per side
  Look look;
};

// the view of an animation (frames: its shapes, at least one) for width x height images: the camera frames
// the union of every frame's bounds, the pool's depth that of the first frame's water
View make_view(std::span<const Shapes> frames, const Look& look, int width, int height);

class Renderer {
 public:
  // GlError if a program fails to build or the framebuffer is incomplete
  Renderer(const gl::Context& context, int width, int height);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // trails: for each ball with trail set, in order, the centres it has passed through
  Image draw(const Shapes& shapes, const std::vector<std::vector<Eigen::Vector3d>>& trails, const View& view);
  // draw's two halves: the GL commands (queued: llvmpipe may still be drawing when this returns), and the
  // read-back, which waits for them
  void render(const Shapes& shapes, const std::vector<std::vector<Eigen::Vector3d>>& trails, const View& view);
  Image read() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace stepwise::render
