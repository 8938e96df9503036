// The report's study: event times and heights of the bouncing ball against its closed form, per method and step or tolerance.
#include "report/studies.hpp"
#include "report/studies/study_scenes.hpp"

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

// a user's scene with events (--scene): each method's event times against a converged reference's (gsl-rk8pd at
// rtol 1e-13, checked by verner98 at the same tolerance), the n-th found against the n-th
StudyOutput user_event_times(const StudyContext& ctx, const StudyScene& scene) {
  const auto model = scene_model(scene);
  const std::vector<double> t_out{scene.t_end};
  const auto events_of = [&](std::string_view method, const StepControl& control) {
    return make_integrator(method, control)->integrate(*model, 0, model->initial_state(), t_out);
  };
  const StepControl fine = StepControl::adaptive(reference_rtol, 1e-3 * reference_rtol);
  const RunResult reference = events_of(reference_method, fine), check = events_of("verner98", fine);
  if (reference.status != Status::ok) throw std::runtime_error(fmt::format("event-times: the reference run of {} ({}) failed: {}", scene.label, reference_method, reference.message));
  double agreement = reference.events.size() == check.events.size() ? 0 : std::numeric_limits<double>::infinity();
  for (size_t n = 0; n < std::min(reference.events.size(), check.events.size()); ++n)
    agreement = std::max(agreement, std::abs(reference.events[n].t - check.events[n].t));

  Table table{{"method", "dt", "rtol", "events", "reference_events", "max_time_error_s", "rhs_evals", "status"}, {}};
  const auto record = [&](const std::string& method, std::optional<double> dt, std::optional<double> rtol, const StepControl& control) {
    const RunResult r = events_of(method, control);
    double error = 0;
    for (size_t n = 0; n < std::min(r.events.size(), reference.events.size()); ++n) error = std::max(error, std::abs(r.events[n].t - reference.events[n].t));
    table.rows.push_back({method, dt ? Cell(*dt) : Cell(std::string()), rtol ? Cell(*rtol) : Cell(std::string()), static_cast<long>(r.events.size()),
                          static_cast<long>(reference.events.size()), error, r.stats.rhs_evals, std::string(to_string(r.status))});
  };
  const double dt0 = scene.time_scale / 4;
  const std::vector<double> dts = ctx.quick ? std::vector<double>{dt0 / 4} : std::vector<double>{dt0, dt0 / 4, dt0 / 16};
  const std::vector<double> rtols = ctx.quick ? std::vector<double>{1e-8} : std::vector<double>{1e-4, 1e-6, 1e-8, 1e-10};
  for (const std::string method : {"euler", "rk4", "gsl-rk8pd"})
    if (method_applies(*find_method(method), *model))
      for (const double dt : dts) record(method, dt, std::nullopt, StepControl::fixed(dt));
  for (const std::string method : {"tsitouras54", "verner98", "rodas5", "cvode-adams", "cvode-bdf", "gsl-rkf45", "gsl-msbdf"})
    if (method_applies(*find_method(method), *model))
      for (const double rtol : rtols) record(method, std::nullopt, rtol, StepControl::adaptive(rtol, rtol * 1e-3));
  std::string md = fmt::format("{} over {} s: each run's event times against {} at rtol {:g} ({} events; {} at the same tolerance agrees to "
                               "{:.2e} s), the n-th found against the n-th. Fixed steps and the hand-written and GSL pairs locate an "
                               "event by re-stepping (their interpolant where they have one) to the root; CVODE by its own root finding.\n\n",
                               scene.label, scene.t_end, reference_method, reference_rtol, reference.events.size(), "verner98", agreement);
  const auto setting = [&](const std::vector<Cell>& row) {
    const Cell& dt = cell_of(table, row, "dt");
    return std::holds_alternative<double>(dt) ? fmt::format("dt {:g}", std::get<double>(dt)) : fmt::format("rtol {:g}", std::get<double>(cell_of(table, row, "rtol")));
  };
  md += markdown_table(table, {{"method", "method"},
                               {"", "dt or rtol", {}, setting},
                               {"events", "events"},
                               {"reference_events", "reference"},
                               {"max_time_error_s", "max time error (s)", shown_as("sci")},
                               {"rhs_evals", "calls of f"},
                               {"status", "status"}});
  return {{{"event_times", std::move(table)}}, md, {}};
}

StudyOutput event_times(const StudyContext& ctx) {
  if (ctx.scenes) return user_event_times(ctx, ctx.scenes->front());
  const bool quick = ctx.quick;
  const Params ball{{"height", 1.0}, {"restitution", 0.8}, {"g", 9.81}, {"rest_speed", 0.01}};
  const auto model = make_model("bouncing-ball", ball);
  const auto exact = bouncing_ball_impacts(ball, 1000);
  const double eps = ball.at("restitution"), g = ball.at("g"), v0 = std::sqrt(2 * g * ball.at("height"));
  // sampled at the exact apexes (after each impact but the last), so the heights are compared where they peak
  std::vector<double> t_out;
  for (size_t n = 0; n + 1 < exact.size(); ++n) t_out.push_back(exact[n].t + std::pow(eps, static_cast<double>(n + 1)) * v0 / g);
  const double t_end = exact.back().t + 0.5;
  t_out.push_back(t_end);

  Table table{{"method", "location", "dt", "rtol", "impacts", "exact_impacts", "max_time_error_s", "max_height_error_m", "rhs_evals", "status"}, {}};
  std::string md = fmt::format("The bouncing ball (h0 = 1 m, eps = {}) has {} impacts, the last ending in rest at {:.4f} s. Each run's "
                               "impact times against the closed form (the n-th found against the n-th exact, over those both have), "
                               "and its heights at the exact apex times against eps^(2n) h0. Fixed steps locate an impact on the "
                               "segment between the step's ends (the seeds' method) or by re-stepping to the root; CVODE finds "
                               "roots itself.\n\n",
                               eps, exact.size(), exact.back().t);
  auto record = [&](const std::string& method, const std::string& location, std::optional<double> dt, std::optional<double> rtol,
                    const StepControl& control) {
    const RunResult r = make_integrator(method, control)->integrate(*model, 0, model->initial_state(), t_out);
    double time_error = 0, height_error = 0;
    const size_t matched = std::min(r.events.size(), exact.size());
    for (size_t n = 0; n < matched; ++n) time_error = std::max(time_error, std::abs(r.events[n].t - exact[n].t));
    for (size_t n = 0; n + 1 < std::min(r.trajectory.y.size(), exact.size()); ++n)
      height_error = std::max(height_error, std::abs(r.trajectory.y[n][0] - exact[n].apex));
    table.rows.push_back({method, location, dt ? Cell(*dt) : Cell(std::string()), rtol ? Cell(*rtol) : Cell(std::string()),
                          static_cast<long>(r.events.size()), static_cast<long>(exact.size()), time_error, height_error,
                          r.stats.rhs_evals, std::string(to_string(r.status))});
  };
  const std::vector<double> dts = quick ? std::vector<double>{1e-3} : std::vector<double>{1e-2, 1e-3, 1e-4};
  const std::vector<double> rtols = quick ? std::vector<double>{1e-8} : std::vector<double>{1e-4, 1e-6, 1e-8, 1e-10};
  for (const std::string method : {"euler", "symplectic-euler", "rk4", "gsl-rk8pd"})
    for (const double dt : dts)
      for (const auto location : {EventLocation::linear, EventLocation::restep}) {
        StepControl control = StepControl::fixed(dt);
        control.event_location = location;
        record(method, location == EventLocation::linear ? "segment" : "restep", dt, std::nullopt, control);
      }
  for (const std::string method : {"cvode-adams", "cvode-bdf", "gsl-rkf45", "gsl-rk8pd"})
    for (const double rtol : rtols) {
      StepControl control = StepControl::adaptive(rtol, rtol * 1e-3);
      control.event_location = EventLocation::restep;
      // CVODE locates events by its own root finding (the family's), the others by restepping
      record(method, find_method(method)->family == Family::cvode ? "rootfinding" : "restep", std::nullopt, rtol, control);
    }
  const auto setting = [&](const std::vector<Cell>& row) {
    const Cell& dt = cell_of(table, row, "dt");
    return std::holds_alternative<double>(dt) ? fmt::format("dt {:g}", std::get<double>(dt))
                                              : fmt::format("rtol {:g}", std::get<double>(cell_of(table, row, "rtol")));
  };
  md += markdown_table(table, {{"method", "method"},
                               {"location", "location"},
                               {"", "dt or rtol", {}, setting},
                               {"impacts", "impacts"},
                               {"max_time_error_s", "max time error (s)", shown_as("sci")},
                               {"max_height_error_m", "max height error (m)", shown_as("sci")}});
  std::vector<Figure> figures;
  md += "\n";
  const auto impact_error = [](std::string x, std::string x_label, std::string title) {
    return FigureSpec::Panel{.title = std::move(title), .x_label = std::move(x_label), .y_label = "largest impact-time error (s)", .log_x = true, .log_y = true,
                             .layers = {{.table = "event_times", .x = x, .y = "max_time_error_s", .series = "method", .split = {"location"},
                                         .split_dashed = true, .label = "{} ({location})", .floor = 1e-17, .complete = {x},
                                         .hover = {{"impacts", "impacts"}, {"rhs_evals", "calls of f"}}}}};
  };
  FigureSpec spec{.title = "The bouncing ball's impact times",
                  .panels = {impact_error("dt", "step dt (s)", "Fixed steps: the impact on the step's segment (solid) or re-stepped to the root (dashed)"),
                             impact_error("rtol", "relative tolerance", "Adaptive: CVODE's root finding, GSL re-stepped")}};
  md += add_figure(figures, "event_times", "", std::move(spec), "Largest impact-time error of the bouncing ball against the step or tolerance, per method and root location");
  return {{{"event_times", std::move(table)}}, md, figures};
}

}  // namespace

Study event_times_study() { return {.name = "event-times", .title = "Events: the bouncing ball's impacts and apexes per method", .run = event_times,
          .scene_problem = [](const StudyScene&, const Model& model) {
            return events_of(model).empty() ? std::string("has no events ([events.NAME] when = \"...\") for the event-times study") : std::string();
          }}; }

}  // namespace stepwise
