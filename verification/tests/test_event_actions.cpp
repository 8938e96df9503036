// An event's own action never fires it again (docs/scenes.md#events, "Location"): the state where an event is
// located sits on the side its formula came from (a left root), and the crossing an action starts from is never a
// new event, under every method that steps a scene's own events and in both event-location modes. Balls whose
// events watch no direction against their closed forms, a ball between two walls for 100 bounces, actions that
// leave the formula exactly zero or where the root put it, and trajectory.csv's rows at an instant.
#include "models/bouncing_ball.hpp"
#include "models/equations.hpp"
#include "models/model.hpp"
#include "run/scene.hpp"
#include "solvers/method_table.hpp"
#include "verification/tolerances.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

namespace stepwise {
namespace {

std::unique_ptr<Model> model_of(const std::string& toml) {
  const Scene scene = load_scene_text(toml, "test.toml");
  return make_equations(*scene.equations, {}, false);
}

struct MethodEventCase {
  std::string method;
  StepControl control;
  double tolerance;  // on an event's time
};

// rk4 at a fixed step (exact on a parabola: its events to round-off), and every adaptive method that takes the
// model (the gpu passes step no events), at rtol 1e-10, or 1e-7 where the method is of order 2 and 1e-5 where of
// order 1: a method whose error estimate is of order 1 takes millions of steps on a parabola at 1e-10
std::vector<MethodEventCase> every_method(const Model& model) {
  std::vector<MethodEventCase> cases{{"rk4", StepControl::fixed(1e-3), tolerance::event_time_exact_steps}};
  for (const Method& method : methods())
    if (method.adaptive() && method.family != Family::gpu && method_applies(method, model)) {
      const double rtol = method.order.max >= 3 ? 1e-10 : method.order.max == 2 ? 1e-7 : 1e-5;
      cases.push_back({std::string(method.name), StepControl::adaptive(rtol, 1e-2 * rtol), tolerance::event_time_per_rtol * rtol});
    }
  return cases;
}

// each case in both event-location modes (the seeds' linear estimate and the re-step: a scene's own events are
// refined in either, and SUNDIALS finds its roots itself)
template <class Check>
void in_both_locations(const std::vector<MethodEventCase>& cases, Check check) {
  for (const EventLocation location : {EventLocation::linear, EventLocation::restep})
    for (MethodEventCase c : cases) {
      c.control.event_location = location;
      check(c, location == EventLocation::linear ? "linear" : "restep");
    }
}

RunResult run(const Model& model, const MethodEventCase& c, std::vector<double> t_out) {
  return make_integrator(c.method, c.control)->integrate(model, 0, model.initial_state(), t_out);
}

std::vector<double> every(double dt, double t_end) {
  std::vector<double> t;
  for (int k = 1; k * dt <= t_end * (1 + 1e-12); ++k) t.push_back(k * dt);
  return t;
}

// balls dropped together from 1.3 m, ball i with restitution e_i and its own floor event watching `direction` ("" for
// none: either way), each coming to rest below rest_speed; `onto_floor`: its action also sets its height to exactly 0
struct Ball {
  double restitution;
  std::string direction;
  bool onto_floor = false;
};
constexpr double drop = 1.3, g = 9.81, rest_speed = 0.05;

std::string balls_scene(const std::vector<Ball>& balls) {
  std::string heights, speeds, initial, equations, events;
  for (size_t i = 0; i < balls.size(); ++i) {
    heights += fmt::format("{}\"y{}\"", i ? ", " : "", i);
    speeds += fmt::format(", \"v{}\"", i);
    initial += fmt::format("y{0} = {1}\nv{0} = 0.0\n", i, drop);
    equations += fmt::format("y{0} = \"v{0}\"\nv{0} = \"-g\"\n", i);
    events += fmt::format("[events.floor{}]\nwhen = \"y{}\"\n", i, i);
    if (!balls[i].direction.empty()) events += fmt::format("direction = \"{}\"\n", balls[i].direction);
    events += fmt::format("action = {{ v{0} = \"-{1}*v{0}\"{3} }}\nrest = \"{1}*abs(v{0}) < {2}\"\n", i, balls[i].restitution, rest_speed,
                          balls[i].onto_floor ? fmt::format(", y{} = \"0\"", i) : "");
  }
  return fmt::format("model = \"equations\"\nvariables = [{}{}]\n[initial]\n{}[parameters]\ng = {}\n[equations]\n{}{}", heights, speeds, initial, g,
                     equations, events);
}

// ball i's impacts: its event's records
std::vector<const EventRecord*> impacts_of(const RunResult& r, size_t ball) {
  std::vector<const EventRecord*> impacts;
  for (const EventRecord& e : r.events)
    if (e.event == ball) impacts.push_back(&e);
  return impacts;
}

// Each ball's impacts as those of the same scene with every floor watching "falling" (which direction an event
// watches does not change what happens), and no ball ever below the floor: at each impact the state where it was
// located is on the side the ball came from (height >= 0, exactly), and at every output within the solution's own
// error. Where the falling twin meets the closed form (every method whose dense output is exact on a parabola),
// so do they: their closed form's times, ending at rest
void expect_closed_form_bounces(const std::vector<Ball>& balls) {
  const auto model = model_of(balls_scene(balls));
  std::vector<Ball> falling = balls;
  for (Ball& ball : falling) ball.direction = "falling";
  const auto twin = model_of(balls_scene(falling));
  double t_end = 0;
  std::vector<std::vector<Bounce>> exact;
  for (const Ball& ball : balls) {
    exact.push_back(bouncing_ball_impacts({{"height", drop}, {"restitution", ball.restitution}, {"g", g}, {"rest_speed", rest_speed}}, 1000));
    t_end = std::max(t_end, exact.back().back().t + 0.25);
  }
  in_both_locations(every_method(*model), [&](const MethodEventCase& c, const char* location) {
    const RunResult r = run(*model, c, every(0.01, t_end)), reference = run(*twin, c, every(0.01, t_end));
    ASSERT_EQ(r.status, reference.status) << c.method << " (" << location << "): " << r.message << " / " << reference.message;
    if (r.status != Status::ok) return;  // failing alike, whatever the direction: the method's own (below)
    for (size_t i = 0; i < balls.size(); ++i) {
      const auto impacts = impacts_of(r, i), expected = impacts_of(reference, i);
      ASSERT_EQ(impacts.size(), expected.size()) << c.method << " (" << location << "): ball " << i << " (e = " << balls[i].restitution << ")";
      bool closed_form = expected.size() == exact[i].size();
      for (size_t n = 0; n < impacts.size(); ++n) {
        EXPECT_NEAR(impacts[n]->t, expected[n]->t, c.tolerance) << c.method << " (" << location << "): ball " << i << ", impact " << n;
        EXPECT_EQ(impacts[n]->kind, expected[n]->kind) << c.method << " (" << location << "): ball " << i << ", impact " << n;
        EXPECT_GE(impacts[n]->before[static_cast<Eigen::Index>(i)], 0.0) << c.method << " (" << location << "): ball " << i << " at " << impacts[n]->t;
        if (balls[i].onto_floor) {
          EXPECT_EQ(impacts[n]->after[static_cast<Eigen::Index>(i)], 0.0) << c.method << " (" << location << ")";
        }
        closed_form = closed_form && std::abs(expected[n]->t - exact[i][n].t) <= c.tolerance;
      }
      if (closed_form) {
        for (size_t n = 0; n < impacts.size(); ++n)
          EXPECT_NEAR(impacts[n]->t, exact[i][n].t, c.tolerance) << c.method << " (" << location << "): ball " << i << ", impact " << n;
        EXPECT_EQ(impacts.back()->kind, "rest") << c.method << " (" << location << "): ball " << i;
      } else {
        std::cout << c.method << " (" << location << "): ball " << i << " off its closed form whatever the direction ("
                  << expected.size() << " impacts of " << exact[i].size() << ")\n";
      }
      // at an output, the solution's own error: an impact time's error bound times the fastest impact's speed
      for (size_t k = 0; k < r.trajectory.t.size(); ++k)
        ASSERT_GE(r.trajectory.y[k][static_cast<Eigen::Index>(i)], -c.tolerance * std::sqrt(2 * g * drop))
            << c.method << " (" << location << "): ball " << i << " below the floor at t = " << r.trajectory.t[k];
    }
  });
}

TEST(EventActions, ThreeBallsOneOfThemWatchingNoDirectionBounceAsTheirClosedForms) {
  // the tracker's scene: two floors watching "falling", the third either way (its located state a hair past the
  // floor, a bounce then crossed back and was reversed 27 times, and the ball fell through the floor)
  expect_closed_form_bounces({{0.9, "falling"}, {0.6, "falling"}, {0.3, ""}});
}

TEST(EventActions, ABallWhoseFloorWatchesNoDirectionBouncesAsTheClosedFormAtRestitutions03And09) {
  for (const double e : {0.3, 0.9}) expect_closed_form_bounces({{e, ""}});
}

// a ball between two walls, x' = vx from 0.5 at 1 m/s, the walls at x = 0 and x = 1 each an event watching
// `right` and `left` ("" for either way)
std::string walls(const std::string& right, const std::string& left) {
  const auto direction = [](const std::string& d) { return d.empty() ? std::string() : "direction = \"" + d + "\"\n"; };
  return R"(model = "equations"
variables = ["x", "vx"]
[initial]
x = 0.5
vx = 1.0
[equations]
x = "vx"
vx = "0"
[events.right]
when = "x - 1"
)" + direction(right) + R"(action = { vx = "-vx" }
[events.left]
when = "x"
)" + direction(left) + R"(action = { vx = "-vx" }
)";
}

TEST(EventActions, ABallBetweenTwoWallsEachWatchingNoDirectionStaysBetweenThemFor100Bounces) {
  // bounce k (k = 0, 1, ...) at t = 0.5 + k, on the right wall for even k. A method that fails alike with the walls
  // watching the way the ball comes fails for a reason of its own, whatever the direction (said, not held here)
  const auto model = model_of(walls("", "")), directed = model_of(walls("rising", "falling"));
  const int bounces = 100;
  in_both_locations(every_method(*model), [&](const MethodEventCase& c, const char* location) {
    const RunResult r = run(*model, c, every(0.25, bounces));
    if (r.status != Status::ok) {
      const RunResult twin = run(*directed, c, every(0.25, bounces));
      ASSERT_EQ(twin.status, r.status) << c.method << " (" << location << "): " << r.message << " / " << twin.message;
      EXPECT_EQ(twin.t_stop, r.t_stop) << c.method << " (" << location << ")";
      std::cout << c.method << " (" << location << "): fails whatever the walls watch: " << r.message << "\n";
      return;
    }
    ASSERT_EQ(r.events.size(), static_cast<size_t>(bounces)) << c.method << " (" << location << ")";
    for (size_t k = 0; k < r.events.size(); ++k) {
      const EventRecord& e = r.events[k];
      ASSERT_EQ(e.event, k % 2) << c.method << " (" << location << "): bounce " << k;
      EXPECT_NEAR(e.t, 0.5 + static_cast<double>(k), tolerance::event_time_linear_motion(e.t)) << c.method << " (" << location << "): bounce " << k;
      // located on the side it came from: inside the box
      EXPECT_TRUE(e.before[0] <= 1 && e.before[0] >= 0) << c.method << " (" << location << "): x = " << e.before[0] << " at bounce " << k;
    }
    // at an output, the solution's own error: the time's at 1 m/s
    for (size_t k = 0; k < r.trajectory.t.size(); ++k)
      ASSERT_TRUE(std::abs(r.trajectory.y[k][0] - 0.5) <= 0.5 + tolerance::event_time_linear_motion(r.trajectory.t[k]))
          << c.method << " (" << location << "): x = " << r.trajectory.y[k][0] << " at t = " << r.trajectory.t[k];
  });
}

// x' = v from 0 at 1 m/s, and events on x - 0.5 (t = 0.5), n counting their firings: `events` their tables
std::unique_ptr<Model> line_with(const std::string& events) {
  return model_of(R"(model = "equations"
variables = ["x", "v", "n"]
[initial]
x = 0.0
v = 1.0
n = 0.0
[equations]
x = "v"
v = "0"
n = "0"
)" + events);
}

TEST(EventActions, AnActionThatLeavesItsFormulaExactlyZeroOrWhereTheRootPutItFiresItOnce) {
  struct Action {
    std::string what, events;
    double x_end;  // x at t = 1
  };
  const std::vector<Action> actions{
      {"counting only (the motion goes on)", "[events.half]\nwhen = \"x - 0.5\"\naction = { n = \"n + 1\" }\n", 1.0},
      {"onto the zero, the motion going on", "[events.half]\nwhen = \"x - 0.5\"\naction = { x = \"0.5\", n = \"n + 1\" }\n", 1.0},
      {"onto the zero, the motion turned back", "[events.half]\nwhen = \"x - 0.5\"\naction = { x = \"0.5\", v = \"-v\", n = \"n + 1\" }\n", 0.0},
      {"turned back where the root put it", "[events.half]\nwhen = \"x - 0.5\"\naction = { v = \"-v\", n = \"n + 1\" }\n", 0.0},
  };
  for (const Action& action : actions) {
    const auto model = line_with(action.events);
    in_both_locations(every_method(*model), [&](const MethodEventCase& c, const char* location) {
      const RunResult r = run(*model, c, {0.25, 0.75, 1.0});
      ASSERT_EQ(r.status, Status::ok) << c.method << " (" << location << "), " << action.what << ": " << r.message;
      ASSERT_EQ(r.events.size(), 1u) << c.method << " (" << location << "), " << action.what;
      EXPECT_NEAR(r.events[0].t, 0.5, tolerance::event_time_linear_motion(0.5)) << c.method << " (" << location << "), " << action.what;
      EXPECT_EQ(r.y_stop[2], 1.0) << c.method << " (" << location << "), " << action.what;
      EXPECT_NEAR(r.y_stop[0], action.x_end, tolerance::event_time_linear_motion(1.0)) << c.method << " (" << location << "), " << action.what;
    });
  }
  // a ball whose action puts it exactly on the floor as it turns it (its formula exactly zero after it)
  expect_closed_form_bounces({{0.5, "", true}});
}

TEST(EventActions, RowsAtAnInstantShowTheStateBeforeItAndAfterAllOfItsActionsNeverBetween) {
  // two identical balls, each with its own floor: both fire at each impact's instant. The sink (trajectory.csv's
  // rows) gets the state before the instant and after both actions, never ball 1 turned and ball 2 not
  const auto model = model_of(balls_scene({{0.8, ""}, {0.8, ""}}));
  for (const MethodEventCase& c : every_method(*model)) {
    std::vector<std::pair<double, Eigen::VectorXd>> rows;
    MethodEventCase sunk = c;
    sunk.control.sink = [&](double t, const Eigen::VectorXd& y) {
      rows.emplace_back(t, y);
      return std::string();
    };
    const RunResult r = run(*model, sunk, every(0.05, 2.0));
    ASSERT_EQ(r.status, Status::ok) << c.method << ": " << r.message;
    ASSERT_GE(r.events.size(), 4u) << c.method;
    for (const auto& [t, y] : rows) {
      ASSERT_EQ(y[0], y[1]) << c.method << " at t = " << t;
      ASSERT_EQ(y[2], y[3]) << c.method << " at t = " << t;
    }
    // each instant's two rows once, whatever the number of its events
    for (size_t n = 0; n < r.events.size(); n += 2) {
      const auto at_instant = std::count_if(rows.begin(), rows.end(), [&](const auto& row) { return row.first == r.events[n].t; });
      EXPECT_EQ(at_instant, 2) << c.method << " at t = " << r.events[n].t;
    }
  }
}

}  // namespace
}  // namespace stepwise
