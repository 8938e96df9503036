// The report's study: adequacy: where the linear wave equation stops being enough.
#include "report/studies.hpp"

#include "models/bouncing_ball.hpp"
#include "models/model.hpp"
#include "models/pendulum.hpp"
#include "models/rigid_body.hpp"
#include "solvers/capabilities/mass_spring.hpp"
#include "solvers/capabilities/second_order.hpp"
#include "solvers/wave_step.hpp"
#include "verification/adequacy.hpp"
#include "verification/contact_checks.hpp"
#include "verification/convergence.hpp"
#include "verification/invariants.hpp"
#include "run/measure.hpp"
#include "verification/stability.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

namespace stepwise {
namespace {

StudyOutput wave_adequacy(const StudyContext& context) {
  const std::vector<double> ratios{1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3};
  std::vector<std::string> labels;
  for (const double r : ratios) labels.push_back(fmt::format("A/H = {:g}", r));
  const auto departures = context.sweep<LinearWaveDeparture>(labels, [&](size_t k) { return linear_wave_departure(-ratios[k]); });
  Table table{{"amplitude_over_depth", "relative_departure", "relative_max_departure", "departure_per_amplitude"}, {}};
  const LinearWaveSetup setup;
  std::string md = fmt::format("The height field's wave equation is the shallow water equations linearised (c^2 = g H). Both are "
                               "run from the same dent of depth A in water of depth H = {} m ({} x {} points, d = {} m, a raised "
                               "cosine of radius {} m, mu = {} /s) by rk4 at dt = {} s to t = {} s, as the ring has crossed most of "
                               "the pool; ", setup.depth, setup.size, setup.size, setup.spacing, setup.radius, setup.mu, setup.dt, setup.t_end);
  md += "the table gives the difference of the surfaces relative to the wave equation's. It grows "
                   "in proportion to A / H (the ratio in the last column holds), so the wave equation is within 1% of "
                   "shallow water below A / H = " + fmt::format("{:.3f}", 0.01 * ratios[0] / departures[0].relative) +
                   " and within 10% below " + fmt::format("{:.2f}", 0.1 * ratios[0] / departures[0].relative) +
                   ": ripples on a pond, not waves on a beach.\n\n";
  for (size_t k = 0; k < ratios.size(); ++k) {
    const auto& d = departures[k];
    table.rows.push_back({ratios[k], d.relative, d.relative_max, d.relative / ratios[k]});
  }
  md += markdown_table(table, {{"amplitude_over_depth", "A / H", shown_as("{:g}")},
                               {"relative_departure", "\\|eta - z\\| / \\|z\\|", shown_as("{:.3e}")},
                               {"relative_max_departure", "max \\|eta - z\\| / max \\|z\\|", shown_as("{:.3e}")},
                               {"departure_per_amplitude", "departure / (A / H)", shown_as("{:.3f}")}});
  std::vector<Figure> figures;
  md += "\n";
  const auto departure = [](std::string column, std::string label) {
    return FigureSpec::Layer{.table = "wave_adequacy", .x = "amplitude_over_depth", .y = std::move(column), .label = std::move(label)};
  };
  FigureSpec spec{.title = "Where the linear wave equation is enough (shallow water as the truth)",
                  .panels = {{.x_label = "drop depth over water depth A / H", .y_label = "departure of the wave equation", .log_x = true, .log_y = true,
                              .layers = {departure("relative_departure", "|eta - z| / |z|"), departure("relative_max_departure", "max |eta - z| / max |z|")},
                              .lines = {{'y', 0.01, "1%"}, {'y', 0.1, "10%"}}}}};
  md += add_figure(figures, "wave_adequacy", "", std::move(spec),
                   "The linear wave equation's departure from shallow water against the drop's depth over the water's");
  // the finding: the departure per unit of A / H, over the drops tried
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& row : table.rows) {
    const double per_amplitude = std::get<double>(cell_of(table, row, "departure_per_amplitude"));
    lo = std::min(lo, per_amplitude);
    hi = std::max(hi, per_amplitude);
  }
  std::vector<std::string> findings{fmt::format(
      "**Model no more than the scene needs**: the height field's linear wave equation departs from shallow water by {:.3f} to {:.3f} times "
      "the drop's depth over the water's (A / H from {:g} to {:g}): ripples on a pond need no more, waves on a beach do.",
      lo, hi, ratios.front(), ratios.back())};
  return {{{"wave_adequacy", std::move(table)}}, md, figures, findings};
}

}  // namespace

Study wave_adequacy_study() { return {"wave-adequacy", "Model adequacy: the wave equation against shallow water", wave_adequacy}; }

}  // namespace stepwise
