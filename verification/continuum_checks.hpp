// The cloth at rest, springs or continuum (models/cloth.cpp), measured as a materials lab measures a sheet:
// its Poisson's ratio and Young's modulus from a uniaxial stretch of a strip, its sag and the narrowing of its
// bottom edge when it hangs from its two top corners. Each is a static equilibrium (solvers/static_equilibrium)
// in the sheet's plane (every z held: the in-plane answer, without the wrinkles a compressed sheet would throw).
#pragma once

#include <stepwise/models/model.hpp>

#include <string>
#include <vector>
#include <tuple>

namespace stepwise {

struct UniaxialStretch {
  double nu = 0;        // -(lateral strain) / strain at the strip's middle
  double E = 0;         // the pull per unit width over (thickness x strain), Pa (for springs: at the `thickness` given)
  double strain = 0;    // the stretch imposed
  int iterations = 0;   // Newton's
  std::string failure;  // empty when the equilibrium was found
  std::vector<double> residuals;  // Newton's relative residuals, iteration by iteration
};
// a strip 4 m long (x) and 1 m wide, `rows` nodes across its width and 4 (rows - 1) + 1 along it, of the cloth
// with `params` (continuum or springs; gravity, wind and drag off), its left end's x held, its right end's
// moved by `strain` of the length, free to narrow (one node's y held against sliding)
UniaxialStretch uniaxial_stretch(Params params, int rows, double strain);
// the strip the report measures a material on: nodes across it, and the strain (small: the linear material's answer)
inline constexpr int material_strip_rows = 9;
inline constexpr double material_strip_strain = 1e-3;
// the continuum cloth of the material `springs` measured as: its E, and its Poisson's ratio kept inside the range
// the model takes
Params continuum_of(const UniaxialStretch& springs);

struct HangingSheet {
  double sag = 0;           // how far the top edge's middle hangs below the pins (m)
  double bottom_width = 0;  // the bottom edge's corners' distance (m; 1 at rest)
  double middle_width = 0;  // the sheet's width halfway down, edge to edge (m; 1 at rest): "the sides shrink inside"
  double bottom_drop = 0;   // how far the bottom edge's middle has moved down (m)
  int iterations = 0;       // Newton's, over the four load steps
  std::string failure;
  static auto fields(auto& s) { return std::tie(s.sag, s.bottom_width, s.middle_width, s.bottom_drop, s.iterations, s.failure); }  // a sweep's result
};
// a 1 m square sheet of side x side nodes hanging in its plane from its two top corners under gravity (applied
// in four steps, each from the last one's equilibrium), the cloth with `params` (wind off)
HangingSheet hanging_sheet(Params params, int side);

// the well-posed hanging sheet: a 1 m square of side x side nodes held along its whole top edge (pin_top_edge),
// hanging in its plane under gravity (four load steps). Hung from two points, plane elasticity is singular there and
// the sag grows with every refinement; held along a line, the finite elements converge
struct ClampedSheet {
  double drop = 0;          // how far the bottom edge's middle has moved down (m)
  double bottom_width = 0;  // the bottom edge's corners' distance (m; 1 at rest)
  double middle_width = 0;  // the width halfway down (m; 1 at rest)
  int iterations = 0;
  std::string failure;
  static auto fields(auto& s) { return std::tie(s.drop, s.bottom_width, s.middle_width, s.iterations, s.failure); }  // a sweep's result
};
ClampedSheet clamped_sheet(Params params, int side);

// Bending against Kirchhoff's plate: a horizontal continuum sheet clamped along its left edge (clamp_left_edge: the first
// two columns pinned, so the edge can neither move nor turn), bending under its own weight q = density thickness g.
// A strip of span L (x) clamped along an edge `aspect` L long (z), `side` nodes along the span. Where the strip is long
// along its clamped edge the middle of the free edge bends as the plate strip does, in cylindrical bending:
//     tip deflection q L^4 / (8 D),   D = E t^3 / (12 (1 - nu^2))
// (Euler-Bernoulli with the plate's rigidity: the strip cannot curl across itself in its middle). Near the free side
// edges the plate curls (anticlastic bending) and softens toward the narrow beam's E t^3 / 12; at nu = 0 the strip's
// answer is exact at every aspect. The deflection is small (the plate's linear theory) when q L^3 / (8 D) << 1.
struct BentStrip {
  double length = 0;          // L, the span from the clamped line (the second column) to the free edge (m)
  double tip_deflection = 0;  // how far the free edge's middle has dropped (m)
  double analytic = 0;        // q L^4 / (8 D) (m)
  int iterations = 0;
  std::string failure;
  static auto fields(auto& s) { return std::tie(s.length, s.tip_deflection, s.analytic, s.iterations, s.failure); }  // a sweep's result
};
BentStrip bent_strip(Params params, int side, double aspect);
// the plate the report and the suite bend: aluminium, 1 cm thick, a 1 m span under Earth's gravity (tip deflection
// 5 mm, 0.5% of the span: linear), clamped along an edge four spans long
Params bending_plate();
inline constexpr double bending_plate_aspect = 4;


}  // namespace stepwise
