// The grid of a PDE scene and where each stencil value of each node comes from (models/pde.hpp): a node of the
// state, a Dirichlet side's value, or a ghost outside a side, a fixed combination of the nodes and values inside it
// and of the side's normal derivative (models/pde.hpp says which). Built once; read at every evaluation of f and of
// its Jacobian.
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
  int node = 0;           // node: the node of the field read; ghost: its combination among FieldBoundary::ghosts
  int position = 0;       // dirichlet and ghost: where along the side its formula is evaluated
};

// a ghost's value: the sum of each term's weight times its value (a node's, or a Dirichlet side's), plus `slope` h
// times the side's outward normal derivative (h the spacing across the side)
struct Ghost {
  std::vector<std::pair<Source, double>> terms;
  double slope = 0;
};

// one field's boundary on the grid: for each node whether it follows a Dirichlet side (then which, and where along
// it), and for each node and slot the source of the stencil value
struct FieldBoundary {
  std::array<bool, 2> periodic{};
  std::array<int, 4> kind{-1, -1, -1, -1};  // per side: -1 none (periodic), else PdeSide::Kind
  std::vector<std::int8_t> dirichlet_side;  // per node: the Dirichlet side it lies on, or -1
  std::vector<int> dirichlet_position;      // per node: its place along that side
  std::vector<Source> sources;              // node-major: sources[node * stencil.size() + slot]
  std::vector<Ghost> ghosts;                // the ghosts' combinations, by Source::node
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
