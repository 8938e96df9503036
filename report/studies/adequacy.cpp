// The report's study: adequacy: where the small-angle model stops being enough.
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

StudyOutput adequacy(const StudyContext&) {
  Table table{{"phase_tolerance_rad", "periods", "max_amplitude_rad", "max_amplitude_deg"}, {}};
  std::string md = "Largest amplitude at which the small-angle pendulum (theta'' = -(g/L) theta) stays within a phase "
                   "error of the exact (elliptic) solution after N periods. Below it the linear model, which costs one "
                   "cosine per sample and no integration at all, is all a scene needs.\n\n";
  for (const double tolerance : {0.01, 0.1, 1.0})
    for (const double periods : {1.0, 10.0, 100.0}) {
      const double amplitude = small_angle_max_amplitude(tolerance, periods);
      table.rows.push_back({tolerance, periods, amplitude, amplitude * 180 / std::numbers::pi});
    }
  md += markdown_table(table, {{"phase_tolerance_rad", "phase tolerance (rad)", shown_as("{:g}")},
                               {"periods", "periods", shown_as("{:.0f}")},
                               {"max_amplitude_deg", "max amplitude (deg)", shown_as("{:.2f}")}});
  std::vector<Figure> figures;
  md += "\n";
  FigureSpec spec{.title = "Where the small-angle pendulum is enough",
                  .panels = {{.x_label = "periods shown", .y_label = "largest amplitude (degrees)", .log_x = true, .log_y = true,
                              .layers = {{.table = "adequacy", .x = "periods", .y = "max_amplitude_deg", .series = "phase_tolerance_rad",
                                          .label = "phase error {} rad"}}}}};
  md += add_figure(figures, "adequacy", "", std::move(spec), "Largest amplitude the small-angle pendulum serves, against the periods shown");
  return {{{"adequacy", std::move(table)}}, md, figures};
}

}  // namespace

Study adequacy_study() { return {"adequacy", "Model adequacy: small-angle pendulum", adequacy}; }

}  // namespace stepwise
