#include "stencil.hpp"

namespace stepwise::pde {

Stencil::Stencil(int order, int dimension) : radius(order / 2) {
  offsets.push_back({0, 0});
  for (int axis = 0; axis < dimension; ++axis)
    for (int d = -radius; d <= radius; ++d)
      if (d != 0) offsets.push_back(axis == 0 ? std::array{d, 0} : std::array{0, d});
}

int Stencil::slot(int dx, int dy) const {
  for (size_t s = 0; s < offsets.size(); ++s)
    if (offsets[s][0] == dx && offsets[s][1] == dy) return static_cast<int>(s);
  return -1;
}

Layout layout_of(const PdeSpec& spec, const std::array<bool, 2>& periodic) {
  Layout grid;
  grid.nx = spec.points[0];
  grid.ny = spec.dimension == 2 ? spec.points[1] : 1;
  for (int axis = 0; axis < spec.dimension; ++axis) {
    const int n = axis == 0 ? grid.nx : grid.ny;
    const auto [a, b] = spec.domain[static_cast<size_t>(axis)];
    grid.origin[static_cast<size_t>(axis)] = a;
    grid.h[static_cast<size_t>(axis)] = (b - a) / (periodic[static_cast<size_t>(axis)] ? n : n - 1);
  }
  return grid;
}

std::array<double, 2> side_point(const Layout& grid, int side, int position) {
  const int i = side == left ? 0 : side == right ? grid.nx - 1 : position;
  const int j = side == bottom ? 0 : side == top ? grid.ny - 1 : (side < 2 ? position : 0);
  return {grid.origin[0] + i * grid.h[0], grid.origin[1] + j * grid.h[1]};
}

namespace {

// the Dirichlet side node (i, j) lies on, the x sides first (a corner follows its left or right side), or -1
int dirichlet_side_of(const Layout& grid, const FieldBoundary& b, int i, int j) {
  const auto value = static_cast<int>(PdeSide::Kind::value);
  if (i == 0 && b.kind[left] == value) return left;
  if (i == grid.nx - 1 && b.kind[right] == value) return right;
  if (grid.ny > 1 && j == 0 && b.kind[bottom] == value) return bottom;
  if (grid.ny > 1 && j == grid.ny - 1 && b.kind[top] == value) return top;
  return -1;
}

// the source of the value at (i + dx, j + dy) seen from (i, j), inside the grid (a periodic axis wrapped)
Source inside(const Layout& grid, const FieldBoundary& b, int i, int j, int dx, int dy) {
  const int axis = dx != 0 ? 0 : 1;
  const int n = axis == 0 ? grid.nx : grid.ny;
  int at = axis == 0 ? i + dx : j + dy;
  if (b.periodic[static_cast<size_t>(axis)]) at = (at % n + n) % n;
  const int ii = axis == 0 ? at : i, jj = axis == 0 ? j : at;
  Source source;
  source.node = jj * grid.nx + ii;
  if (const int side = dirichlet_side_of(grid, b, ii, jj); side >= 0) {
    source.kind = Source::Kind::dirichlet;
    source.side = static_cast<std::int8_t>(side);
    source.position = side < 2 ? jj : ii;
  }
  return source;
}

// the weights of the values k = 0, 1, ... inside a side (the side's node first) and of h times its outward normal
// derivative g that make the ghost k outside it. Order 2: the mirror, u_-k = u_k + 2 k h g, which keeps the
// central stencils' second order at a Neumann side. Order 4: past a Neumann side the two ghosts that make the
// five-point first derivative at the side -g and the six-point fifth difference through them zero; past a
// Dirichlet side the quartic through the side's value and four nodes inside. Each is exact on quartics (a ghost's
// error O(h^5)), so a neighbour's second difference errs by O(h^3) at the side, its first by O(h^4): the order 4
// holds over the grid (a boundary's truncation error may be an order below the interior's, Gustafsson 1975)
std::pair<std::vector<double>, double> ghost_weights(int order, bool neumann, int k) {
  if (order == 2) {
    std::vector<double> w(static_cast<size_t>(k) + 1, 0.0);
    w[static_cast<size_t>(k)] = 1;
    return {w, neumann ? 2.0 * k : 0.0};
  }
  if (neumann) {
    if (k == 1) return {{-10.0 / 3, 6.0, -2.0, 1.0 / 3}, 4.0};
    return {{-80.0 / 3, 40.0, -15.0, 8.0 / 3}, 20.0};
  }
  if (k == 1) return {{5.0, -10.0, 10.0, -5.0, 1.0}, 0.0};
  return {{15.0, -40.0, 45.0, -24.0, 5.0}, 0.0};
}

// the source of the value at (i + dx, j + dy) seen from (i, j): inside the grid, or a ghost outside a side, made
// from the values along the same line inside it
Source source_of(const Layout& grid, FieldBoundary& b, int order, int i, int j, int dx, int dy) {
  const int axis = dx != 0 ? 0 : 1;
  const int n = axis == 0 ? grid.nx : grid.ny;
  const int at = axis == 0 ? i + dx : j + dy;
  if ((at >= 0 && at < n) || b.periodic[static_cast<size_t>(axis)]) return inside(grid, b, i, j, dx, dy);
  const int side = axis == 0 ? (at < 0 ? left : right) : (at < 0 ? bottom : top);
  const int k = at < 0 ? -at : at - (n - 1);
  const int inward = at < 0 ? 1 : -1, edge = at < 0 ? 0 : n - 1;
  const auto [weights, slope] = ghost_weights(order, b.kind[static_cast<size_t>(side)] == static_cast<int>(PdeSide::Kind::derivative), k);
  Ghost ghost{{}, slope};
  for (size_t m = 0; m < weights.size(); ++m) {
    if (weights[m] == 0) continue;
    const int to = edge + inward * static_cast<int>(m) - (axis == 0 ? i : j);
    ghost.terms.emplace_back(axis == 0 ? inside(grid, b, i, j, to, 0) : inside(grid, b, i, j, 0, to), weights[m]);
  }
  Source source;
  source.kind = Source::Kind::ghost;
  source.side = static_cast<std::int8_t>(side);
  source.position = axis == 0 ? j : i;
  source.node = static_cast<int>(b.ghosts.size());
  b.ghosts.push_back(std::move(ghost));
  return source;
}

}  // namespace

FieldBoundary field_boundary(const Layout& grid, const Stencil& stencil, const PdeBoundary& boundary) {
  FieldBoundary b;
  b.periodic = boundary.periodic;
  for (int side = 0; side < 4; ++side)
    if (const auto& condition = boundary.sides[static_cast<size_t>(side)]) b.kind[static_cast<size_t>(side)] = static_cast<int>(condition->kind);
  const int nodes = grid.nodes(), slots = stencil.size();
  b.dirichlet_side.assign(static_cast<size_t>(nodes), -1);
  b.dirichlet_position.assign(static_cast<size_t>(nodes), 0);
  b.sources.resize(static_cast<size_t>(nodes) * static_cast<size_t>(slots));
  for (int j = 0; j < grid.ny; ++j)
    for (int i = 0; i < grid.nx; ++i) {
      const auto node = static_cast<size_t>(j * grid.nx + i);
      const int side = dirichlet_side_of(grid, b, i, j);
      b.dirichlet_side[node] = static_cast<std::int8_t>(side);
      b.dirichlet_position[node] = side < 0 ? 0 : side < 2 ? j : i;
      for (int s = 0; s < slots; ++s) {
        const auto& o = stencil.offsets[static_cast<size_t>(s)];
        b.sources[node * static_cast<size_t>(slots) + static_cast<size_t>(s)] = source_of(grid, b, stencil.radius * 2, i, j, o[0], o[1]);
      }
    }
  return b;
}

}  // namespace stepwise::pde
