#include "continuum_checks.hpp"

#include "solvers/capabilities/mass_spring.hpp"
#include "solvers/capabilities/second_order.hpp"
#include "solvers/static_equilibrium.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace stepwise {

namespace {

// every position coordinate z held: the sheet stays in its plane
std::vector<bool> in_plane(Eigen::Index coordinates) {
  std::vector<bool> held(static_cast<size_t>(coordinates), false);
  for (Eigen::Index i = 2; i < coordinates; i += 3) held[static_cast<size_t>(i)] = true;
  return held;
}

}  // namespace

UniaxialStretch uniaxial_stretch(Params params, int rows, double strain) {
  const int columns = 4 * (rows - 1) + 1;
  for (const auto& [key, value] : Params{{"rows", rows}, {"columns", columns}, {"width", 4.0}, {"height", 1.0}, {"pin_corners", 0},
                                         {"g", 0}, {"wind_coefficient", 0}, {"drag", 0}})
    params[key] = value;
  params = resolve_params(*find_model("cloth"), params);
  const auto model = make_model("cloth", params);
  Eigen::VectorXd y = model->initial_state();
  const Eigen::Index n = y.size() / 2;
  // every node free, row-major: node (r, c) at 3 (r columns + c)
  const auto at = [&](int r, int c) { return 3 * (Eigen::Index{r} * columns + c); };
  const double left = y[at(0, 0)];
  for (Eigen::Index i = 0; i < n; i += 3) y[i] = left + (y[i] - left) * (1 + strain);  // the affine stretch: the first guess
  std::vector<bool> held = in_plane(n);
  for (int r = 0; r < rows; ++r) held[static_cast<size_t>(at(r, 0))] = held[static_cast<size_t>(at(r, columns - 1))] = true;
  held[static_cast<size_t>(at(rows / 2, 0) + 1)] = true;
  const StaticEquilibrium eq = static_equilibrium(*model, y, held);
  UniaxialStretch out;
  out.strain = strain;
  out.iterations = eq.iterations;
  out.failure = eq.failure;
  out.residuals = eq.residuals;
  const int middle = (columns - 1) / 2;
  const double width = eq.y[at(0, middle) + 1] - eq.y[at(rows - 1, middle) + 1];
  out.nu = -(width / params.at("height") - 1) / strain + 0.0;  // + 0: a ratio of 0 is shown as 0, not -0
  // the pull on the right end: minus the sheet's force on its held x
  Eigen::VectorXd a(n);
  model->as<SecondOrderView>()->acceleration(0, eq.y, a);
  const auto& mass = model->as<MassSpringView>()->mass;
  double pull = 0;
  for (int r = 0; r < rows; ++r) pull -= a[at(r, columns - 1)] * mass[static_cast<size_t>(at(r, columns - 1) / 3)];
  out.E = pull / (params.at("height") * params.at("thickness") * strain);
  return out;
}

Params continuum_of(const UniaxialStretch& springs) {
  return {{"continuum", 1}, {"E", springs.E}, {"nu", std::clamp(springs.nu, -0.9, 0.49)}};
}

namespace {

// the cloth with `params` under gravity applied in `steps` steps, each from the last one's equilibrium (its in-plane
// shortening found before the next load bends it further): the state, Newton's iterations, and why not where it failed
struct Hung {
  Eigen::VectorXd y;
  int iterations = 0;
  std::string failure;
  double top = 0;  // the top row's height (m)
};
Hung settle_under_gravity(Params params, int steps, bool in_plane_only) {
  params = resolve_params(*find_model("cloth"), params);
  const double g = params.at("g");
  Hung out;
  out.top = params.at("elevation");
  for (int step = 1; step <= steps; ++step) {
    params["g"] = g * step / steps;
    const auto model = make_model("cloth", params);
    if (out.y.size() == 0) out.y = model->initial_state();
    const Eigen::Index n = out.y.size() / 2;
    const StaticEquilibrium eq = static_equilibrium(*model, out.y, in_plane_only ? in_plane(n) : std::vector<bool>(static_cast<size_t>(n), false));
    out.iterations += eq.iterations;
    out.y = eq.y;
    if (!eq.failure.empty()) {
      out.failure = fmt::format("g = {}: {}", params["g"], eq.failure);
      break;
    }
  }
  return out;
}

// a 1 m square sheet of side x side nodes held by `support` (its pins' parameters), hanging in its plane under gravity
// applied in four steps
Hung hang_in_plane(Params params, int side, const Params& support) {
  for (const auto& [key, value] : Params{{"rows", side}, {"columns", side}, {"width", 1.0}, {"height", 1.0}, {"pin_corners", 0}, {"wind_coefficient", 0}})
    params[key] = value;
  for (const auto& [key, value] : support) params[key] = value;
  return settle_under_gravity(std::move(params), 4, true);
}

// the heights and widths of a hung sheet's rows, `at(r, c)` the state index of grid node (r, c)'s x
template <class At>
struct Rows {
  const Eigen::VectorXd& y;
  int side;
  At at;
  double middle_y(int r) const { return side % 2 ? y[at(r, side / 2) + 1] : (y[at(r, side / 2 - 1) + 1] + y[at(r, side / 2) + 1]) / 2; }
  double width(int r) const { return y[at(r, side - 1)] - y[at(r, 0)]; }
  double middle_width() const { return side % 2 ? width(side / 2) : (width(side / 2 - 1) + width(side / 2)) / 2; }
};
template <class At>
Rows(const Eigen::VectorXd&, int, At) -> Rows<At>;

}  // namespace

HangingSheet hanging_sheet(Params params, int side) {
  const Hung hung = hang_in_plane(std::move(params), side, {{"pin_top_corners", 1}});
  // the two top corners pinned: grid node k is state node k - 1 on the top row, k - 2 below it
  const Rows rows{hung.y, side, [side](int r, int c) {
                    const int k = r * side + c;
                    return 3 * Eigen::Index{r == 0 ? k - 1 : k - 2};
                  }};
  HangingSheet out;
  out.iterations = hung.iterations;
  out.failure = hung.failure;
  out.sag = hung.top - rows.middle_y(0);
  out.bottom_width = rows.width(side - 1);
  out.middle_width = rows.middle_width();
  out.bottom_drop = (hung.top - 1) - rows.middle_y(side - 1);
  return out;
}

ClampedSheet clamped_sheet(Params params, int side) {
  const Hung hung = hang_in_plane(std::move(params), side, {{"pin_top_edge", 1}});
  // the top row pinned: grid node k (below it) is state node k - side
  const Rows rows{hung.y, side, [side](int r, int c) { return 3 * Eigen::Index{r * side + c - side}; }};
  ClampedSheet out;
  out.iterations = hung.iterations;
  out.failure = hung.failure;
  out.drop = (hung.top - 1) - rows.middle_y(side - 1);
  out.bottom_width = rows.width(side - 1);
  out.middle_width = rows.middle_width();
  return out;
}

Params bending_plate() { return {{"continuum", 1}, {"E", 7e10}, {"nu", 0.33}, {"thickness", 0.01}, {"density", 2700}, {"g", 9.81}}; }

BentStrip bent_strip(Params params, int side, double aspect) {
  const double span = 1;
  const int rows = static_cast<int>(std::lround(aspect * (side - 1))) + 1;
  for (const auto& [key, value] : Params{{"rows", rows}, {"columns", side}, {"width", span}, {"height", aspect * span}, {"horizontal", 1},
                                         {"pin_corners", 0}, {"clamp_left_edge", 1}, {"wind_coefficient", 0}, {"drag", 0}})
    params[key] = value;
  params = resolve_params(*find_model("cloth"), params);
  const Hung bent = settle_under_gravity(params, 1, false);
  BentStrip out;
  out.iterations = bent.iterations;
  out.failure = bent.failure;
  const Eigen::VectorXd& y = bent.y;
  // the first two columns pinned: grid node (r, c) is state node r (side - 2) + c - 2
  const auto height = [&](int r) { return y[3 * (Eigen::Index{r} * (side - 2) + side - 3) + 1]; };
  const double tip = rows % 2 ? height(rows / 2) : (height(rows / 2 - 1) + height(rows / 2)) / 2;
  out.tip_deflection = params.at("elevation") - tip;
  out.length = span * (side - 2) / (side - 1);
  // the closed form's own rigidity, written from the plate theory and not taken from the model's material
  const double E = params.at("E"), nu = params.at("nu"), t = params.at("thickness");
  const double D = E * t * t * t / (12 * (1 - nu * nu)), q = params.at("density") * t * params.at("g");
  out.analytic = q * std::pow(out.length, 4) / (8 * D);
  return out;
}

}  // namespace stepwise
