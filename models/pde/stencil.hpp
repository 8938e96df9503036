// The grid of a PDE scene and where each stencil value of each node comes from (models/pde.hpp): a node of the
// state, a Dirichlet side's value, or a Neumann side's ghost (a node mirrored through the side, plus 2 k h times the
// side's normal derivative). Built once; read at every evaluation of f and of its Jacobian.
#pragma once

#include "models/pde.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace stepwise::pde {

enum Side : int { left = 0, right = 1, bottom = 2, top = 3 };

// the stencil's offsets, the same for every field: the centre, then along x -r..-1, 1..r, then along y
struct Stencil {
  int radius = 1;
  std::vector<std::array<int, 2>> offsets;
  Stencil(int order, int dimension);
  int size() const { return static_cast<int>(offsets.size()); }
  int slot(int dx, int dy) const;  // the slot of an offset, or -1
};

// where a stencil value comes from
struct Source {
  enum class Kind : std::uint8_t { node, dirichlet, ghost };
  Kind kind = Kind::node;
  std::int8_t side = -1;  // dirichlet and ghost: the side (Side)
  std::int8_t k = 0;      // ghost: how far outside the side
  int node = 0;           // node and ghost: the node of the field read (the mirror for a ghost)
  int position = 0;       // dirichlet and ghost: where along the side its formula is evaluated
};

// one field's boundary on the grid: for each node whether it follows a Dirichlet side (then which, and where along
// it), and for each node and slot the source of the stencil value
struct FieldBoundary {
  std::array<bool, 2> periodic{};
  std::array<int, 4> kind{-1, -1, -1, -1};  // per side: -1 none (periodic), else PdeSide::Kind
  std::vector<std::int8_t> dirichlet_side;  // per node: the Dirichlet side it lies on, or -1
  std::vector<int> dirichlet_position;      // per node: its place along that side
  std::vector<Source> sources;              // node-major: sources[node * stencil.size() + slot]
};

// the nodes and spacings: a periodic axis of n points spans [a, b) at h = (b - a) / n; another [a, b] at
// h = (b - a) / (n - 1)
struct Layout {
  int nx = 0, ny = 1;
  std::array<double, 2> h{1, 1};
  std::array<double, 2> origin{};
  int nodes() const { return nx * ny; }
  int along(int side) const { return side < 2 ? ny : nx; }  // the nodes along a side
};
Layout layout_of(const PdeSpec& spec, const std::array<bool, 2>& periodic);

// a side's nodes' coordinates (x, y), by position along it
std::array<double, 2> side_point(const Layout& grid, int side, int position);

FieldBoundary field_boundary(const Layout& grid, const Stencil& stencil, const PdeBoundary& boundary);

}  // namespace stepwise::pde
