// A user's own PDE, written as text in a scene file (docs/scenes.md, "Your own PDE"), by the method of lines:
//
//   model = "pde"
//   fields = ["u", "v"]                      # the unknown fields
//   [grid]  x = [0, 1]  y = [0, 1]  points = 128 (or [nx, ny])  order = 2 (or 4)
//   [boundary.u]  x = "periodic"  left = { value = "0" }  right = { derivative = "0" }  (bottom, top in 2-D)
//   [initial]  u = "exp(-100*(x - 0.5)^2)"    # formulas of x (and y) and the parameters
//   [parameters]  D = 0.01
//   [equations]  u = "D*laplace(u) - upwind_dx(a, u)"   # du/dt, pointwise
//   [exact]  u = "..."                        # optional: the solution, a formula of x, y and t
//
// The nodes. A periodic axis of n points has them at a + i h, h = (b - a) / n (b is a's image); any other axis at
// a + i h, h = (b - a) / (n - 1), both ends nodes. A Dirichlet side's nodes follow their formula (the stencils of
// their neighbours read its value, and the node's own rate is its time derivative, so the state holds it); a
// Neumann side's nodes are unknowns. A stencil reaching past a side reads a ghost, a fixed combination of the values
// inside (models/pde/stencil.cpp): at order 2 the mirror through a Neumann side, u_{-k} = u_k - 2 k h du/dx (du/dx
// from the outward normal derivative given); at order 4 (five-point stencils) ghosts exact on quartics, from the
// side's derivative or its value: each order holds over the grid, its sides included.
//
// The operators (dx, dy, dxx, dyy, laplace: central differences of the grid's order; upwind_dx(a, f), upwind_dy:
// a times the one-sided first difference against the flow, the side by the sign of `a` at each node) become
// expressions of the stencil's values, which GiNaC parses, differentiates (the exact sparse Jacobian: each
// formula by each stencil value) and turns into tapes (models/equations/tape.hpp). The right-hand side is the
// pointwise formula applied at every node in one loop: compiled once through the equations model's cache,
// whatever the grid (the spacings are parameters of the C), or interpreted where no compiler is.
#pragma once

#include <stepwise/models/equations.hpp>
#include <stepwise/models/model.hpp>

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace stepwise {

// one side of one field's boundary: a value (Dirichlet) or an outward normal derivative (Neumann), a formula of
// t and of the coordinate along the side
struct PdeSide {
  enum class Kind { value, derivative };
  Kind kind = Kind::value;
  Formula formula;
};

// a field's boundary: an axis is periodic, or each of its two sides has a condition
struct PdeBoundary {
  std::array<bool, 2> periodic{};             // x, y
  std::array<std::optional<PdeSide>, 4> sides;  // left, right, bottom, top
  std::string where;                          // "file:line: boundary.u"
};

// the scene file's PDE, as written (checked on making the model)
struct PdeSpec {
  std::string file;
  std::vector<std::string> fields;
  std::string fields_where;
  int dimension = 1;                            // 1, or 2 where [grid] has y
  std::array<std::array<double, 2>, 2> domain{};  // x = [a, b], y = [a, b]
  std::array<std::string, 2> domain_where;
  std::array<int, 2> points{0, 1};              // nodes along x and y
  std::string points_where;
  int order = 2;                                // the central stencils' order: 2 or 4
  std::string order_where;
  std::vector<std::pair<std::string, PdeBoundary>> boundary;  // by field
  std::vector<Formula> initial, equations, exact;
  Params parameters;
};

// the most nodes a PDE scene may have on all fields together (a state of 2^26 doubles, 512 MiB: past that the
// Jacobian and a method's vectors would not fit in memory)
inline constexpr double max_pde_unknowns = 1 << 26;

// the model with `values` (parameters by name; `points`, `order` override the grid) applied. BadParameter naming
// the key for an unknown name or a bad value, BadEquations naming the file, line and key for a formula or a
// boundary at fault, before anything is compiled
std::unique_ptr<Model> make_pde(const PdeSpec& spec, const Params& values, bool compile = true);

// the grid of a PDE model: its fields, nodes and coordinates (grid.csv, field_NAME.csv, the pictures)
struct PdeGrid {
  std::vector<std::string> fields;
  int nx = 0, ny = 1;
  std::vector<double> x, y;  // each node's coordinates, row-major (node = j nx + i)
  std::array<std::array<double, 2>, 2> domain{};  // x = [a, b], y = [a, b] (y = [0, 0] in 1-D)
  std::array<bool, 2> periodic{};                // by axis
  // the PDE's own solution on the nodes at t, from [exact]; empty without one. It is the solution of the PDE, not
  // of the grid's ODE system (the model's has_exact() is false): an error against it holds the grid's error
  std::function<Eigen::VectorXd(double t)> exact;
  int nodes() const { return nx * ny; }
};
const PdeGrid* pde_grid(const Model& model);

// where the pictures put field f of a grid: 2-D fields side by side along x, each over its domain shifted by
// f times 1.1 of the domain's length (the same for a 1-D grid's space-time pictures)
double drawn_offset(const PdeGrid& grid, size_t field);

}  // namespace stepwise
