// The report's study: wave stability: the largest stable dt of the seeds' two height-field schemes, against mu.
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

StudyOutput wave_stability_limits(const StudyContext& ctx) {
  const bool quick = ctx.quick;
  const int points = 32;
  const long steps = quick ? 1000 : 3000;
  const std::vector<double> mus = quick ? std::vector<double>{0, 0.5, 2, 10} : std::vector<double>{0, 0.5, 1, 2, 5, 10, 20, 50};
  Table table{{"method", "c", "d", "mu", "measured_dt", "derived_dt", "seeds_dt", "measured_over_derived", "seeds_over_measured"}, {}};
  std::string md = fmt::format(
      "The largest stable dt found by bisection (to 0.1%: {} steps from a random field on {}^2 points stay within 1e6 of "
      "the start), beside the limit derived from each scheme's amplification of its highest mode (solvers/wave_step.hpp) "
      "and the seeds' condition dt < (mu + sqrt(mu^2 + 32 c^2/d^2)) / (8 c^2/d^2).\n\n",
      steps, points);
  double worst_derived = 0, seeds_at_rest = 0, seeds_damped = 0;
  struct Point {
    std::string method;
    double c, d, mu;
  };
  std::vector<Point> plan;
  std::vector<std::string> labels;
  // the methods whose limit on a height field is derived (the method table's wave_dt), on the CPU (the GPU's
  // passes run the same schemes in float32)
  for (const std::string& method :
       method_names_where([](const Method& m) { return m.source == Source::hand_written && static_cast<bool>(m.stability.wave_dt); }))
    for (const auto& [c, d] : {std::pair{1.0, 0.02}, {2.0, 0.05}})
      for (const double mu : mus) {
        plan.push_back({method, c, d, mu});
        labels.push_back(fmt::format("{} c {:g} d {:g} mu {:g}", method, c, d, mu));
      }
  const auto found = ctx.sweep<WaveStability>(labels, [&](size_t i) {
    const Point& p = plan[i];
    return wave_stability(p.method, points, p.d, p.c, p.mu, steps);
  });
  for (size_t i = 0; i < plan.size(); ++i) {
    const auto& [method, c, d, mu] = plan[i];
    const WaveStability& w = found[i];
    table.rows.push_back({method, c, d, mu, w.measured, w.derived, w.seeds, w.measured / w.derived, w.seeds / w.measured});
    worst_derived = std::max(worst_derived, std::abs(w.measured / w.derived - 1));
    if (mu == 0) seeds_at_rest = std::max(seeds_at_rest, 1 - w.seeds / w.derived);
    else seeds_damped = std::max(seeds_damped, w.seeds / w.measured - 1);
  }
  md += markdown_table(table, {{"method", "method"},
                               {"c", "c (m/s)", shown_as("{}")},
                               {"d", "d (m)", shown_as("{}")},
                               {"mu", "mu (1/s)", shown_as("{}")},
                               {"measured_dt", "measured dt (s)", shown_as("{:.5g}")},
                               {"derived_dt", "derived (s)", shown_as("{:.5g}")},
                               {"seeds_dt", "seeds' (s)", shown_as("{:.5g}")},
                               {"measured_over_derived", "measured / derived", shown_as("{:.4f}")},
                               {"seeds_over_measured", "seeds' / measured", shown_as("{:.4f}")}});
  md += fmt::format(
      "\nThe derived limits hold to {:.2f}% everywhere. The seeds' condition is right without damping (its 8 c^2/d^2 "
      "bounds the grid's highest eigenvalue from above, so it errs safe, by {:.2f}%), and wrong with damping: it grows with "
      "mu while neither scheme's limit does (the three-level scheme's is independent of mu; symplectic Euler's, damping "
      "explicit, shrinks), and promises up to {:.1f}% more than the schemes give — a run at the seeds' dt diverges. It is the "
      "limit of the scheme with the damping taken implicitly.\n\n",
      100 * worst_derived, 100 * seeds_at_rest, 100 * seeds_damped);
  std::vector<Figure> figures;
  const auto limit = [](std::string column, std::string label, FigureMark mark) {
    return FigureSpec::Layer{.table = "wave_stability", .x = "mu", .y = std::move(column), .series = "method", .label = std::move(label), .mark = mark};
  };
  FigureSpec spec{.title = "The height field's largest stable step against damping",
                  .panels = {{.title = "c = {c} m/s, d = {d} m", .x_label = "damping mu (1/s)", .y_label = "largest stable dt (s)", .symlog_x = true,
                              .layers = {limit("measured_dt", "{}: measured", FigureMark::points), limit("derived_dt", "{}: derived", FigureMark::line),
                                         {.table = "wave_stability", .x = "mu", .y = "seeds_dt", .label = "seeds' condition", .mark = FigureMark::line, .dashed = true}}}},
                  .facet = {"c", "d"}};
  md += add_figure(figures, "wave_stability", "", std::move(spec), "Largest stable step of the height field against damping: measured, derived, the seeds' condition");
  return {{{"wave_stability", std::move(table)}}, md, figures};
}

}  // namespace

Study wave_stability_study() { return {"wave-stability", "Stability: the height field's largest stable step against damping", wave_stability_limits}; }

}  // namespace stepwise
