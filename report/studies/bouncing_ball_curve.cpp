// The report's study: the seeds' animated bouncing ball against the physical one.
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

StudyOutput bouncing_ball_curve(const StudyContext&) {
  // the seeds' OpenGL example animates y(p) = A |cos(w p)| e^(-k p): its bounces (zeros of cos) are equally
  // spaced, pi / w apart, and its apexes fall by e^(-k pi / w) per bounce. Matched to the physical ball of
  // height A and restitution eps on the first rebound (flight 2 eps v0 / g) and on the apex ratio (eps^2),
  // the curve keeps every flight as long as the first, where the ball's shrink by eps each bounce.
  const Params ball{{"height", 1.0}, {"restitution", 0.8}, {"g", 9.81}, {"rest_speed", 0.01}};
  const auto impacts = bouncing_ball_impacts(ball, 1000);
  const double eps = ball.at("restitution"), g = ball.at("g");
  const double v0 = std::sqrt(2 * g * ball.at("height"));
  const double spacing = 2 * eps * v0 / g;           // the curve's pi / w
  const double k = -2 * std::log(eps) / spacing;     // e^(-k pi / w) = eps^2
  Table table{{"bounce", "physical_flight_s", "curve_flight_s", "curve_over_physical_flight", "physical_apex_m", "curve_apex_m"}, {}};
  std::string md = fmt::format("The seeds' OpenGL bouncing ball is an animation curve, y = A |cos(w p)| e^(-k p), not physics. "
                               "Matched to the physical ball (h0 = 1 m, eps = {}) on the first rebound's flight ({:.3f} s) and "
                               "on the apex ratio eps^2 per bounce (k = {:.3f} 1/s), its apexes agree bounce for bounce, "
                               "but its flights never shorten: the ball's shrink by eps each bounce and stop after {} impacts "
                               "at {:.3f} s, while the curve bounces on forever at a constant rhythm.\n\n",
                               eps, spacing, k, impacts.size(), impacts.back().t);
  for (size_t n = 0; n + 1 < impacts.size(); ++n) {
    const double flight = impacts[n + 1].t - impacts[n].t;
    const double apex = impacts[n].apex;
    const double curve_apex = ball.at("height") * std::exp(-k * spacing * static_cast<double>(n + 1));
    table.rows.push_back({static_cast<long>(n + 1), flight, spacing, spacing / flight, apex, curve_apex});
  }
  // the first five bounces and the last
  md += markdown_table(table,
                       {{"bounce", "bounce"},
                        {"physical_flight_s", "physical flight (s)", shown_as("{:.4f}")},
                        {"curve_flight_s", "curve flight (s)", shown_as("{:.4f}")},
                        {"curve_over_physical_flight", "curve / physical", shown_as("{:.2f}")}},
                       [&](size_t row) { return row < 5 || row + 1 == table.rows.size(); });
  std::vector<Figure> figures;
  md += "\n";
  const auto ball_and_curve = [](std::string physical, std::string curve) {
    return std::vector<FigureSpec::Layer>{{.table = "bouncing_ball_curve", .x = "bounce", .y = std::move(physical), .label = "physical ball"},
                                          {.table = "bouncing_ball_curve", .x = "bounce", .y = std::move(curve), .label = "seeds' curve"}};
  };
  FigureSpec spec{.title = "The seeds' bouncing ball against the physical one",
                  .panels = {{.title = "Flights: the curve's never shorten", .x_label = "bounce", .y_label = "flight time (s)",
                              .layers = ball_and_curve("physical_flight_s", "curve_flight_s")},
                             {.title = "Apexes: matched bounce for bounce", .x_label = "bounce", .y_label = "apex height (m)", .log_y = true,
                              .layers = ball_and_curve("physical_apex_m", "curve_apex_m")}}};
  md += add_figure(figures, "bouncing_ball_curve", "", std::move(spec), "The seeds' animation curve against the physical ball, bounce by bounce");
  return {{{"bouncing_ball_curve", std::move(table)}}, md, figures};
}

}  // namespace

Study bouncing_ball_curve_study() { return {"bouncing-ball-curve", "Model adequacy: the seeds' animated bouncing ball", bouncing_ball_curve}; }

}  // namespace stepwise
