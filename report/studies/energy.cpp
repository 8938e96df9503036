// The report's study: energy: the pendulum over many periods.
#include "report/studies.hpp"
#include "report/studies/study_scenes.hpp"
#include "run/scene.hpp"

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

StudyOutput energy(const StudyContext& ctx) {
  const bool quick = ctx.quick;
  const int periods = quick ? 100 : 1000;
  const int samples = 20;  // per period: the error oscillates within a period, so one sample a period would alias it
  const double theta0 = 0.5;
  // the pendulum over many periods; or the user's scene (--scene, with an energy formula) over its t_end at a
  // quarter of its fastest time scale, 2000 samples
  const StudyScene* user = ctx.scenes ? &ctx.scenes->front() : nullptr;
  const auto model = user ? scene_model(*user) : make_model("pendulum", {{"theta0", theta0}});
  if (user && !model->energy(model->initial_state()))
    throw InputError(fmt::format("--scene: {} has no energy formula (energy = \"...\" above its first table) for the energy study", user->label));
  const double period = user ? 0 : pendulum_period(theta0, 9.81, 1.0);
  const double dt = user ? user->time_scale / 4 : period / 100, t_end = user ? user->t_end : periods * period;
  const double sample_dt = user ? t_end / 2000 : period / samples;
  const double e0 = *model->energy(model->initial_state());
  const double scale = e0 != 0 ? std::abs(e0) : 1;  // relative to |E0| (an energy may be negative: the double pendulum's)
  Table table{{"method", "t", "relative_energy_error"}, {}};
  Table summary{{"method", "max_first_tenth", "max_last_tenth", "at_end"}, {}};
  std::string md = user ? fmt::format("{} over {} s, dt = {:.3g} s (a quarter of its fastest time scale): the largest relative energy error "
                                      "|E - E0|/|E0| over the first and the last tenth of the run (2000 samples), and the error at the end.\n\n",
                                      user->label, t_end, dt)
                        : fmt::format("Pendulum at theta0 = {} rad over {} periods, dt = T/100: the largest relative energy error "
                               "|E - E0|/E0 over the first and the last tenth of the run ({} samples a period), and the "
                               "error at the end. A symplectic method keeps it bounded; explicit Euler's grows and "
                               "implicit Euler's decays towards the bottom of the well (-1).\n\n",
                               theta0, periods, samples);
  // the hand-written fixed-step methods whose stability is known in closed form (an R(z) or a mass-spring mode's
  // limit): explicit, symplectic and implicit Euler and rk4, each that applies to the model
  for (const std::string& method : method_names_where([&](const Method& m) {
         return m.source == Source::hand_written && m.stepping == Stepping::fixed && (m.stability.R || m.stability.oscillator_dt) && method_applies(m, *model);
       })) {
    StepControl control;
    control.dt = dt;
    const Measured m = run_and_measure(*model, method, control, t_end, sample_dt);
    const auto& ys = m.result.trajectory.y;
    std::vector<double> errors;
    for (size_t i = 0; i < ys.size(); ++i) {
      errors.push_back((*model->energy(ys[i]) - e0) / scale);
      table.rows.push_back({method, m.result.trajectory.t[i], errors.back()});
    }
    auto max_abs = [&](size_t begin, size_t end) {
      double v = 0;
      for (size_t i = begin; i < end; ++i) v = std::max(v, std::abs(errors[i]));
      return v;
    };
    const size_t n = errors.size(), tenth = n / 10;
    const double first = max_abs(0, tenth), last = max_abs(n - tenth, n), end = errors.empty() ? NAN : errors.back();
    summary.rows.push_back({method, first, last, end});
  }
  md += markdown_table(summary, {{"method", "method"},
                                 {"max_first_tenth", "max over first tenth", shown_as("{:.3e}")},
                                 {"max_last_tenth", "max over last tenth", shown_as("{:.3e}")},
                                 {"at_end", "at the end", shown_as("{:+.3e}")}});
  std::vector<Figure> figures;
  md += "\n";
  FigureSpec spec{.title = "Relative energy error over the run, per method (the text above gives the scene and the step)",
                  .panels = {{.x_label = "t (s)", .y_label = "|E - E0| / |E0|", .log_y = true,
                              .layers = {{.table = "energy", .x = "t", .y = "relative_energy_error", .series = "method", .mark = FigureMark::line,
                                          .y_of = "abs", .floor = 1e-17}}}}};
  md += add_figure(figures, "energy", "", std::move(spec), fmt::format("Relative energy error of {} over time, per method", user ? user->label : "the pendulum"));
  // the finding (the pendulum's): symplectic Euler's bounded error against explicit Euler's growth and implicit Euler's decay
  std::vector<std::string> findings;
  std::map<std::string, std::vector<double>> by_method;
  for (const auto& row : summary.rows) {
    const auto value = [&](const char* column) { return std::get<double>(cell_of(summary, row, column)); };
    by_method[std::get<std::string>(cell_of(summary, row, "method"))] = {value("max_first_tenth"), value("max_last_tenth"), value("at_end")};
  }
  if (!user && by_method.contains("symplectic-euler") && by_method.contains("euler") && by_method.contains("implicit-euler"))
    findings.push_back(fmt::format("**Symplectic Euler keeps the energy bounded**: over {} periods of the pendulum at dt = T/100 its relative "
                                   "energy error is {:.3e} at most in the first tenth of the run and {:.3e} in the last, while explicit Euler's "
                                   "grows to {:.3e} and implicit Euler's ends at {:+.3e}, the same first-order accuracy either way.",
                                   periods, by_method["symplectic-euler"][0], by_method["symplectic-euler"][1], by_method["euler"][1],
                                   by_method["implicit-euler"][2]));
  return {{{"energy", std::move(table)}, {"energy_summary", std::move(summary)}}, md, figures, findings};
}

}  // namespace

Study energy_study() { return {.name = "energy", .title = "Energy over long runs", .run = energy, .scene_problem = [](const StudyScene&, const Model& model) {
            return model.energy(model.initial_state()) ? std::string() : std::string("has no energy formula (energy = \"...\" above its first table) for the energy study");
          }}; }

}  // namespace stepwise
