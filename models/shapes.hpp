// What a model's state looks like in space: balls, solid bodies, open surfaces, rods, the ground, a container
// and a water surface, all in world coordinates (m). A model describes this; render/ draws it.
#pragma once

#include <stepwise/models/plane_collision.hpp>
#include <stepwise/models/triangle_mesh.hpp>

#include <Eigen/Dense>

#include <array>
#include <optional>
#include <vector>

namespace stepwise {

struct Shapes {
  struct Ball {
    Eigen::Vector3d center;  // m
    double radius = 0;       // m; 0: a point particle, drawn at a size the view chooses
    bool trail = false;      // draw the path it has come along
  };
  struct Body {
    const TriangleMesh* mesh = nullptr;  // closed, in the body frame (owned by the model)
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // body to world
    Eigen::Vector3d position = Eigen::Vector3d::Zero();      // world position of the body frame's origin (m)
  };
  struct Water {
    int points = 0;          // grid points per side; heights z row-major, x along a row
    double spacing = 0;      // grid spacing d (m): node (i, j) at (j d, i d, z)
    Eigen::VectorXd z;       // points^2 heights (m) about the still level z = 0
  };

  // a scalar on a grid of nx x ny nodes (a fluid's density or vorticity, a PDE's field), drawn as a texture over
  // a rectangle in the plane z = 0. Along a periodic axis of n nodes they sit at origin + i extent / n (the
  // texture repeats); along any other at origin + i extent / (n - 1), both sides nodes
  struct Field {
    int nx = 0, ny = 0;      // values row-major, x along a row
    Eigen::Vector2d origin = Eigen::Vector2d::Zero();  // the rectangle's corner (m)
    Eigen::Vector2d extent = Eigen::Vector2d::Zero();  // its sides along x and y (m)
    std::array<bool, 2> periodic{true, true};
    Eigen::VectorXd values;  // nx ny
    bool is_signed = false;  // a diverging colour map about 0 (vorticity); else a smoke-like one from its low end
    // the values at the colour map's two ends; none: [0, max |v|] (or +-max |v| signed) of the frame drawn
    std::optional<std::array<double, 2>> range;
    bool same_range = false;  // an animation holds one range, its fields' least and greatest over all its frames
  };

  std::vector<Ball> balls;
  std::vector<Body> bodies;
  std::vector<TriangleMesh> surfaces;            // open deforming sheets (cloth), world coordinates, two-sided
  std::vector<std::vector<Eigen::Vector3d>> lines;  // rods and strings, as polylines (m)
  std::optional<Plane> ground;
  std::optional<Aabb> container;                 // the walls of a box, drawn as its edges
  std::optional<Water> water;
  std::vector<Field> fields;                     // side by side, as the model places them
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // against gravity: the camera's up
  bool planar = false;                           // everything in the plane z = 0: seen face on
};

}  // namespace stepwise
