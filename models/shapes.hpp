// What a model's state looks like in space: balls, solid bodies, open surfaces, rods, the ground, a container
// and a water surface, all in world coordinates (m). A model describes this; render/ draws it.
#pragma once

#include <stepwise/models/plane_collision.hpp>
#include <stepwise/models/triangle_mesh.hpp>

#include <Eigen/Dense>

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

  // a scalar on a periodic square grid (a fluid's density or vorticity), drawn as a texture over the square
  // [0, L)^2 in the plane z = 0
  struct Field {
    int points = 0;          // per side; values row-major, x along a row: node (i, j) at (j L / points, i L / points)
    double length = 0;       // L (m)
    Eigen::VectorXd values;  // points^2
    bool is_signed = false;  // a diverging colour map about 0 (vorticity); else a smoke-like one from 0
  };

  std::vector<Ball> balls;
  std::vector<Body> bodies;
  std::vector<TriangleMesh> surfaces;            // open deforming sheets (cloth), world coordinates, two-sided
  std::vector<std::vector<Eigen::Vector3d>> lines;  // rods and strings, as polylines (m)
  std::optional<Plane> ground;
  std::optional<Aabb> container;                 // the walls of a box, drawn as its edges
  std::optional<Water> water;
  std::optional<Field> field;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // against gravity: the camera's up
  bool planar = false;                           // everything in the plane z = 0: seen face on
};

}  // namespace stepwise
