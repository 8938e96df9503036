// A pinhole camera and the look of a picture (light, colours, the pool's depth): the scene file's [render]
// table, each key with a default chosen from what is drawn.
#pragma once

#include <stepwise/models/shapes.hpp>

#include <Eigen/Dense>

#include <functional>
#include <optional>

namespace stepwise::render {

// what the scene file may set; anything unset is chosen from the shapes
struct Look {
  std::optional<Eigen::Vector3d> eye, target, up;  // camera (m); up defaults to the shapes' up
  double fov_deg = 35;                             // vertical field of view
  std::optional<Eigen::Vector3d> light;            // direction towards a distant light (world)
  Eigen::Vector3f color{0.85f, 0.33f, 0.18f};      // balls, bodies and the sheet's front (linear RGB 0-1)
  Eigen::Vector3f background{0.96f, 0.96f, 0.94f};
  std::optional<double> pool_depth;                // water: floor below the still level (m); default side / 4
};

struct Camera {
  Eigen::Vector3d eye, target, up;
  double fov_deg = 35;
  // clip coordinates of world points for an image of this aspect (width / height); near and far from depth_range
  Eigen::Matrix4f view_projection(double aspect) const;
  // where a world point lands in a width x height image: (column, row) from the top-left corner, in pixels
  Eigen::Vector2d pixel(const Eigen::Vector3d& p, int width, int height) const;
  double near = 0.01, far = 100;
};

// the pool a water surface is drawn in: floor at z = -depth under the grid's square [0, side]^2, walls up to
// a rim above the still level, set in a block reaching `border` beyond them, its top (the deck) at the rim:
// it hides the walls' outsides and the floor beyond the surface
struct Pool {
  double side, depth, rim, border;
  Pool(const Shapes::Water& water, double depth_)
      : side((water.points - 1) * water.spacing), depth(depth_), rim(0.15 * depth_), border(0.2 * side) {}
};

// the box around everything drawn: balls, bodies, sheets, rods, the container, the water and its pool
Aabb bounds(const Shapes& shapes, double pool_depth);

// every point drawn at a place the state sets, in an order fixed by the shapes' structure: the balls' centres,
// the bodies' mesh vertices (world), the sheets' vertices, the rods' points, the water's grid nodes
void for_each_point(const Shapes& shapes, const std::function<void(const Eigen::Vector3d&)>& visit);

// the largest distance in pixels, in a width x height image through `camera`, between the points of `a` and
// the same points of `b` (for_each_point): how far one picture of a scene is from another of the same scene;
// NaN if they do not have the same points or a point is not finite
double pixel_distance(const Shapes& a, const Shapes& b, const Camera& camera, int width, int height);

// the pool's depth: the look's, else a quarter of the water's side
double pool_depth(const Shapes& shapes, const Look& look);

// a camera seeing all of `box` (the union of the frames' bounds): face on for a planar scene, else from
// in front and above; the look's eye, target and up win
Camera frame_camera(const Aabb& box, const Shapes& shapes, const Look& look, double aspect);

// towards the light: the look's, else from above, to the left and in front of the camera
Eigen::Vector3d light_direction(const Camera& camera, const Look& look);

}  // namespace stepwise::render
