// Events in a scene's own equations ([events.NAME], docs/scenes.md): the bouncing ball written as equations
// against its closed form and the built-in model, the accumulation time with a rest rule, Zeno without one, and
// the cases event location gets wrong elsewhere: a graze, a double root, an event at t0, two events in one step,
// a terminal event with output times; events at one instant (docs/scenes.md#events): every one fires there, once,
// in the order the file declares them, so a scene symmetric under swapping two bodies stays so to the bit.
#include "models/bouncing_ball.hpp"
#include "models/equations.hpp"
#include "models/model.hpp"
#include "run/scene.hpp"
#include "solvers/method_table.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace stepwise {
namespace {

std::unique_ptr<Model> model_of(std::string_view toml, const Params& values = {}) {
  const Scene scene = load_scene_text(toml, "test.toml");
  return make_equations(*scene.equations, values, false);
}

std::unique_ptr<Model> ball_equations(const Params& values = {}) {
  return make_equations(*load_scene(std::string(STEPWISE_SOURCE_DIR) + "/scenes/bouncing-ball-equations.toml").equations, values, false);
}

RunResult run(const Model& model, std::string_view method, const StepControl& control, std::vector<double> t_out) {
  return make_integrator(method, control)->integrate(model, 0, model.initial_state(), t_out);
}

const Params ball{{"height", 1.0}, {"restitution", 0.8}, {"g", 9.81}, {"rest_speed", 0.01}};

TEST(EquationEvents, TheBallsImpactTimesAreTheClosedFormsToTheMethodsTolerance) {
  const auto exact = bouncing_ball_impacts(ball, 1000);
  const auto model = ball_equations();
  const auto builtin = make_model("bouncing-ball", ball);
  const double t_end = exact.back().t + 0.5;
  struct Case {
    const char* method;
    StepControl control;
    double tolerance;
  };
  const double rtol = 1e-10;
  const std::vector<Case> cases{
      {"rk4", StepControl::fixed(1e-3), tolerance::event_time_exact_steps},
      {"gsl-rk8pd", StepControl::fixed(1e-2), tolerance::event_time_exact_steps},
      {"tsitouras54", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"verner98", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"rodas5", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"cvode-adams", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"cvode-bdf", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"arkode-erk-dormand-prince54", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"odeint-dopri5", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"gsl-rkf45", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
      {"gsl-msbdf", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
  };
  for (const Case& c : cases) {
    const RunResult r = run(*model, c.method, c.control, {t_end});
    const RunResult b = run(*builtin, c.method, c.control, {t_end});
    ASSERT_EQ(r.status, Status::ok) << c.method << ": " << r.message;
    ASSERT_EQ(r.events.size(), exact.size()) << c.method;
    double worst = 0, worst_builtin = 0;
    for (size_t n = 0; n < exact.size(); ++n) {
      worst = std::max(worst, std::abs(r.events[n].t - exact[n].t));
      if (n < b.events.size()) worst_builtin = std::max(worst_builtin, std::abs(r.events[n].t - b.events[n].t));
    }
    std::cout << c.method << ": impact times off by " << worst << " (the built-in model's by " << worst_builtin << ")\n";
    EXPECT_LT(worst, c.tolerance) << c.method;
    EXPECT_EQ(r.events.back().kind, "rest") << c.method;
    // the states just before and after each impact are kept: the rebound is -e times the impact speed
    for (const auto& e : r.events) {
      if (e.kind == "crossing") { EXPECT_NEAR(e.after[1], -0.8 * e.before[1], 1e-12) << c.method << " at " << e.t; }
    }
    // at rest: the ball stays on the floor (vy held at 0, the flag set)
    EXPECT_EQ(r.y_stop[1], 0.0) << c.method;
    EXPECT_EQ(r.y_stop[2], 1.0) << c.method;
    EXPECT_LT(std::abs(r.y_stop[0]), 1e-9) << c.method;
  }
}

TEST(EquationEvents, WithARestRuleTheBallRestsAtTheAccumulationTime) {
  // t_inf = t1 (1 + e) / (1 - e); the rest comes at the impact whose rebound e v_r is below rest_speed, short of
  // t_inf by the flights it would still have made, 2 e v_r / (g (1 - e)) < 2 rest_speed / (g (1 - e))
  const double e = 0.8, g = 9.81, rest_speed = 1e-4;
  const auto model = ball_equations({{"rest_speed", rest_speed}});
  const double t1 = std::sqrt(2 / g), t_inf = t1 * (1 + e) / (1 - e);
  const double rtol = 1e-10;
  for (const char* method : {"verner98", "cvode-bdf", "rodas5"}) {
    const RunResult r = run(*model, method, StepControl::adaptive(rtol, 1e-12), {t_inf + 1});
    ASSERT_EQ(r.status, Status::ok) << method << ": " << r.message;
    ASSERT_EQ(r.events.back().kind, "rest") << method;
    const double short_of = t_inf - r.events.back().t;
    std::cout << method << ": rests " << short_of << " s before t_inf after " << r.events.size() << " impacts\n";
    EXPECT_GE(short_of, -tolerance::event_time_per_rtol * rtol) << method;
    EXPECT_LT(short_of, 2 * rest_speed / (g * (1 - e)) + tolerance::event_time_per_rtol * rtol) << method;
  }
}

TEST(EquationEvents, WithoutARestRuleTheBallIsZenoAndTheRunFailsSayingWhen) {
  const auto model = model_of(R"(model = "equations"
variables = ["y", "v"]
[initial]
y = 1.0
v = 0.0
[equations]
y = "v"
v = "-9.81"
[events.floor]
when = "y"
direction = "falling"
action = { v = "-0.8*v" }
)");
  const double t_inf = std::sqrt(2 / 9.81) * 9;
  for (const char* method : {"rk4", "verner98", "tsitouras54", "gsl-rk8pd"}) {
    StepControl control = std::string_view(method) == "rk4" ? StepControl::fixed(1e-3) : StepControl::adaptive(1e-10, 1e-12);
    const RunResult r = run(*model, method, control, {5.0});
    EXPECT_EQ(r.status, Status::failed) << method << " ends " << to_string(r.status) << " with " << r.events.size() << " events";
    EXPECT_NE(r.message.find("Zeno"), std::string::npos) << r.message;
    EXPECT_NEAR(r.t_stop, t_inf, 1e-3) << method;
  }
}

// x' = 1 from 0: g(x) is g(t), each root known
std::string line_with(std::string_view events) {
  return std::string(R"(model = "equations"
variables = ["x"]
[initial]
x = 0.0
[equations]
x = "1"
)") + std::string(events);
}

TEST(EquationEvents, APairOfRootsInsideOneStepIsFoundByTheExtremumBetween) {
  // (x - 1)^2 - d^2: roots at 1 - d and 1 + d, both inside one step of 0.3 from 0.9, where g is positive at
  // both ends
  const auto model = model_of(line_with("[events.graze]\nwhen = \"(x - 1)^2 - 1e-6\"\n"));
  for (const char* method : {"rk4", "gsl-rk8pd"}) {
    const RunResult r = run(*model, method, StepControl::fixed(0.3), {1.5});
    ASSERT_EQ(r.events.size(), 2u) << method;
    EXPECT_NEAR(r.events[0].t, 0.999, tolerance::event_time_located(0.3)) << method;
    EXPECT_NEAR(r.events[1].t, 1.001, tolerance::event_time_located(0.3)) << method;
  }
  const RunResult adaptive = run(*model, "tsitouras54", StepControl::adaptive(1e-8, 1e-10), {1.5});
  ASSERT_EQ(adaptive.events.size(), 2u);
  EXPECT_NEAR(adaptive.events[0].t, 0.999, 1e-9);
  EXPECT_NEAR(adaptive.events[1].t, 1.001, 1e-9);
}

TEST(EquationEvents, ADoubleRootIsFoundOnce) {
  // (x - 1)^2 touches zero at t = 1 without crossing it: it reaches the level once
  const auto model = model_of(line_with("[events.touch]\nwhen = \"(x - 1)^2\"\n"));
  const RunResult r = run(*model, "rk4", StepControl::fixed(0.3), {2.0});
  ASSERT_EQ(r.events.size(), 1u);
  EXPECT_NEAR(r.events[0].t, 1.0, 1e-6);  // an extremum is flat: its place is found to sqrt of round-off
}

TEST(EquationEvents, AnEventAtTheStartDoesNotFireUnlessItCrosses) {
  // g = x is 0 at t0 and leaves it: no crossing; g = x - 0.5 crosses at 0.5
  const auto model = model_of(line_with("[events.start]\nwhen = \"x\"\n[events.half]\nwhen = \"x - 0.5\"\ndirection = \"rising\"\n"));
  for (const char* method : {"rk4", "tsitouras54", "cvode-bdf"}) {
    const bool fixed = std::string_view(method) == "rk4";
    const RunResult r = run(*model, method, fixed ? StepControl::fixed(0.1) : StepControl::adaptive(1e-8, 1e-10), {1.0});
    ASSERT_EQ(r.events.size(), 1u) << method;
    EXPECT_EQ(events_of(*model)[r.events[0].event].name, "half") << method;
    EXPECT_NEAR(r.events[0].t, 0.5, 1e-9) << method;
  }
}

TEST(EquationEvents, TwoEventsInOneStepAreAppliedInTimeOrder) {
  // both inside one step of 1: b (at 0.2) before a (at 0.3), whatever their order in the file; each action
  // reads the state of its own time
  const auto model = model_of(R"(model = "equations"
variables = ["x", "seen"]
[initial]
x = 0.0
seen = 0.0
[equations]
x = "1"
seen = "0"
[events.a]
when = "x - 0.3"
action = { seen = "10*seen + 1" }
[events.b]
when = "x - 0.2"
action = { seen = "10*seen + 2" }
)");
  for (const char* method : {"rk4", "euler"}) {
    const RunResult r = run(*model, method, StepControl::fixed(1.0), {1.0});
    ASSERT_EQ(r.events.size(), 2u) << method;
    EXPECT_EQ(events_of(*model)[r.events[0].event].name, "b") << method;
    EXPECT_NEAR(r.events[0].t, 0.2, tolerance::event_time_located(1.0)) << method;
    EXPECT_NEAR(r.events[1].t, 0.3, tolerance::event_time_located(1.0)) << method;
    EXPECT_EQ(r.y_stop[1], 21.0) << method << ": b's action, then a's";
  }
}

TEST(EquationEvents, ATerminalEventEndsTheRunThereWithTheOutputsBeforeIt) {
  const auto model = model_of(line_with("[events.stop]\nwhen = \"x - 0.55\"\nterminal = true\n"));
  for (const char* method : {"rk4", "tsitouras54", "cvode-adams", "gsl-rkf45"}) {
    const bool fixed = std::string_view(method) == "rk4";
    const RunResult r = run(*model, method, fixed ? StepControl::fixed(0.1) : StepControl::adaptive(1e-8, 1e-10),
                            {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0});
    ASSERT_EQ(r.status, Status::ok) << method << ": " << r.message;
    EXPECT_TRUE(r.terminated) << method;
    EXPECT_NEAR(r.t_stop, 0.55, 1e-9) << method;
    ASSERT_EQ(r.trajectory.t.size(), 5u) << method;
    EXPECT_EQ(r.trajectory.t.back(), 0.5) << method;
  }
}

TEST(EquationEvents, WithRecordedStepsTheTrajectoryIsTheStepsTaken) {
  const auto model = ball_equations();
  StepControl control = StepControl::adaptive(1e-8, 1e-10);
  control.record_steps = true;
  for (const char* method : {"tsitouras54", "cvode-bdf", "rk4"}) {
    StepControl c = std::string_view(method) == "rk4" ? StepControl::fixed(0.01) : control;
    c.record_steps = true;
    const RunResult r = run(*model, method, c, {2.0});
    ASSERT_EQ(r.status, Status::ok) << method;
    // every step's end, each event's time among them, and the last output time
    EXPECT_GE(static_cast<long>(r.trajectory.t.size()), r.stats.steps) << method;
    EXPECT_EQ(r.trajectory.t.back(), 2.0) << method;
    for (size_t k = 1; k < r.trajectory.t.size(); ++k) ASSERT_GT(r.trajectory.t[k], r.trajectory.t[k - 1]) << method;
    for (const auto& e : r.events)
      EXPECT_TRUE(std::find(r.trajectory.t.begin(), r.trajectory.t.end(), e.t) != r.trajectory.t.end()) << method << ": the event at " << e.t;
  }
}

// two balls dropped together from 1 m, each with its own floor event: the same impacts at the same instants
std::unique_ptr<Model> two_balls() {
  return model_of(R"(model = "equations"
variables = ["y1", "y2", "v1", "v2"]
[initial]
y1 = 1.0
y2 = 1.0
v1 = 0.0
v2 = 0.0
[parameters]
g = 9.81
e = 0.8
[equations]
y1 = "v1"
y2 = "v2"
v1 = "-g"
v2 = "-g"
[events.floor1]
when = "y1"
direction = "falling"
action = { v1 = "-e*v1" }
[events.floor2]
when = "y2"
direction = "falling"
action = { v2 = "-e*v2" }
)");
}

struct EventCase {
  const char* method;
  StepControl control;
  double tolerance;  // on an event's time
};

std::vector<EventCase> instant_cases() {
  const double rtol = 1e-9;
  return {{"rk4", StepControl::fixed(1e-3), tolerance::event_time_exact_steps},
          {"verner98", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
          {"tsitouras54", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
          {"gsl-rk8pd", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
          {"cvode-bdf", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol},
          {"arkode-erk-dormand-prince54", StepControl::adaptive(rtol, 1e-12), tolerance::event_time_per_rtol * rtol}};
}

TEST(EquationEvents, TwoBallsDroppedTogetherStayTogetherToTheBitThroughEveryImpact) {
  // impacts at t1 = sqrt(2/g), then t_{k+1} = t_k + 2 e^k sqrt(2 g) / g: 0.4515, 1.1740, 1.7520 s before t = 2
  const double g = 9.81, e = 0.8;
  std::vector<double> impacts{std::sqrt(2 / g)};
  for (int k = 1; k < 3; ++k) impacts.push_back(impacts.back() + 2 * std::pow(e, k) * std::sqrt(2 * g) / g);
  const auto model = two_balls();
  std::vector<double> t_out;
  for (int k = 1; k <= 40; ++k) t_out.push_back(0.05 * k);
  for (const EventCase& c : instant_cases()) {
    const RunResult r = run(*model, c.method, c.control, t_out);
    ASSERT_EQ(r.status, Status::ok) << c.method << ": " << r.message;
    ASSERT_EQ(r.events.size(), 6u) << c.method << ": each ball's floor once at each of the three impacts";
    for (size_t n = 0; n < 3; ++n) {
      const EventRecord &first = r.events[2 * n], &second = r.events[2 * n + 1];
      EXPECT_EQ(first.event, 0u) << c.method << ": floor1 first, as declared";
      EXPECT_EQ(second.event, 1u) << c.method;
      EXPECT_EQ(first.t, second.t) << c.method << ": one instant";
      EXPECT_NEAR(first.t, impacts[n], c.tolerance) << c.method;
      // each rebound is e times its own impact speed, once
      EXPECT_NEAR(first.after[2], -e * first.before[2], 1e-12) << c.method;
      EXPECT_NEAR(second.after[3], -e * second.before[3], 1e-12) << c.method;
    }
    for (size_t k = 0; k < r.trajectory.t.size(); ++k) {
      const Eigen::VectorXd& y = r.trajectory.y[k];
      ASSERT_EQ(y[0], y[1]) << c.method << " at " << r.trajectory.t[k];
      ASSERT_EQ(y[2], y[3]) << c.method << " at " << r.trajectory.t[k];
    }
  }
}

TEST(EquationEvents, ParticlesDroppedFlatReachTheFloorAtOneInstantAndStayLevelToTheBit) {
  // four particles of particles-in-box at rest at one height, apart in x and y (the state: each particle's x, y, z,
  // then each one's velocity): each has its own floor event, all
  // cross at one instant, and their heights and vertical speeds stay equal to the bit through the bounces
  const int count = 4;
  const auto box = make_model("particles-in-box", {{"count", count}, {"friction", 0.0}});
  Eigen::VectorXd y0 = Eigen::VectorXd::Zero(6 * count);
  for (int i = 0; i < count; ++i) {
    y0[3 * i] = 0.2 + 0.2 * i;      // x
    y0[3 * i + 1] = 0.8 - 0.2 * i;  // y
    y0[3 * i + 2] = 0.7;            // z
  }
  for (const char* method : {"rk4", "symplectic-euler", "verner98"}) {
    const bool fixed = std::string_view(method) != "verner98";
    const RunResult r = make_integrator(method, fixed ? StepControl::fixed(1e-3) : StepControl::adaptive(1e-9, 1e-12))
                            ->integrate(*box, 0, y0, std::vector<double>{0.5, 1.0, 1.5, 2.0});
    ASSERT_EQ(r.status, Status::ok) << method << ": " << r.message;
    ASSERT_GE(r.events.size(), 2u * count) << method;
    ASSERT_EQ(r.events.size() % count, 0u) << method << ": every particle at every impact";
    for (size_t n = 0; n < r.events.size(); n += count)
      for (int i = 1; i < count; ++i) EXPECT_EQ(r.events[n + i].t, r.events[n].t) << method;
    for (const Eigen::VectorXd& y : r.trajectory.y)
      for (int i = 1; i < count; ++i) {
        ASSERT_EQ(y[3 * i + 2], y[2]) << method;                    // height
        ASSERT_EQ(y[3 * count + 3 * i + 2], y[3 * count + 2]) << method;  // vertical speed
      }
  }
}

// x' = 1 from 0 and events on x - 0.5 (t = 0.5): `events` their tables
std::unique_ptr<Model> at_half(std::string_view events) {
  return model_of(std::string(R"(model = "equations"
variables = ["x", "s"]
[initial]
x = 0.0
s = 0.0
[equations]
x = "1"
s = "0"
)") + std::string(events));
}

std::vector<std::string> fired_names(const Model& model, const RunResult& r) {
  std::vector<std::string> names;
  for (const auto& e : r.events) names.push_back(events_of(model)[e.event].name);
  return names;
}

TEST(EquationEvents, EventsCrossingAtOneInstantAllFireThereOnce) {
  // p = x - 0.5 rising and q = 0.5 - x falling: one instant, both recorded, neither twice
  const auto model = at_half("[events.p]\nwhen = \"x - 0.5\"\n[events.q]\nwhen = \"0.5 - x\"\n");
  for (const EventCase& c : instant_cases()) {
    const RunResult r = run(*model, c.method, c.control, {1.0});
    ASSERT_EQ(r.status, Status::ok) << c.method << ": " << r.message;
    EXPECT_EQ(fired_names(*model, r), (std::vector<std::string>{"p", "q"})) << c.method;
    ASSERT_EQ(r.events.size(), 2u) << c.method;
    EXPECT_NEAR(r.events[0].t, 0.5, c.tolerance) << c.method;
    EXPECT_EQ(r.events[1].t, r.events[0].t) << c.method;
  }
  // rk4 at dt 0.1 lands on 0.5 at a step's end: both reach zero there
  const RunResult r = run(*model, "rk4", StepControl::fixed(0.1), {1.0});
  EXPECT_EQ(fired_names(*model, r), (std::vector<std::string>{"p", "q"}));
}

TEST(EquationEvents, ATerminalEventAmongOthersAtItsInstantEndsTheRunAfterThemAll) {
  const auto model = at_half("[events.p]\nwhen = \"x - 0.5\"\n[events.q]\nwhen = \"0.5 - x\"\nterminal = true\n"
                             "[events.r]\nwhen = \"2*x - 1\"\naction = { s = \"1\" }\n");
  for (const EventCase& c : instant_cases()) {
    const RunResult r = run(*model, c.method, c.control, {0.25, 0.75, 1.0});
    ASSERT_EQ(r.status, Status::ok) << c.method << ": " << r.message;
    EXPECT_EQ(fired_names(*model, r), (std::vector<std::string>{"p", "q", "r"})) << c.method;
    EXPECT_TRUE(r.terminated) << c.method;
    EXPECT_NEAR(r.t_stop, 0.5, c.tolerance) << c.method;
    EXPECT_EQ(r.y_stop[1], 1.0) << c.method << ": the state after every handler of the instant";
  }
}

TEST(EquationEvents, ActionsAtOneInstantApplyInTheDeclaredOrderEachOnce) {
  // a's action moves x past its level: b was already at zero at the instant, so it fires all the same, after a,
  // reading the state a left. Declared a then b: s = 10*(1) + 2 = 12; b then a: 10*(2) + 1 = 21
  const std::string a = "[events.a]\nwhen = \"x - 0.5\"\naction = { s = \"10*s + 1\", x = \"x + 0.25\" }\n";
  const std::string b = "[events.b]\nwhen = \"x - 0.5\"\naction = { s = \"10*s + 2\" }\n";
  for (const auto& [file, expected] : {std::pair{a + b, 12.0}, std::pair{b + a, 21.0}}) {
    const auto model = at_half(file);
    for (const EventCase& c : instant_cases()) {
      const RunResult r = run(*model, c.method, c.control, {1.0});
      ASSERT_EQ(r.status, Status::ok) << c.method << ": " << r.message;
      ASSERT_EQ(r.events.size(), 2u) << c.method;
      EXPECT_EQ(r.events[1].t, r.events[0].t) << c.method;
      EXPECT_EQ(r.y_stop[1], expected) << c.method;
      EXPECT_NEAR(r.y_stop[0], 1.25, 1e-9) << c.method;
    }
  }
}

TEST(EquationEvents, AnEventThatIsNotFiniteIsRefusedAtTheStartAndFailsTheRunWhereItBecomesSo) {
  try {
    (void)model_of(line_with("[events.e]\nwhen = \"sqrt(x - 2)\"\n"));
    FAIL() << "an event that is nan at the start was accepted";
  } catch (const std::exception& error) {
    EXPECT_NE(std::string(error.what()).find("event 'e'"), std::string::npos) << error.what();
  }
  // sqrt(1 - x) is finite until x = 1 (t = 1), then nan
  const auto model = model_of(line_with("[events.e]\nwhen = \"sqrt(1 - x)\"\n"));
  for (const char* method : {"rk4", "verner98", "cvode-bdf"}) {
    const bool fixed = std::string_view(method) == "rk4";
    const RunResult r = run(*model, method, fixed ? StepControl::fixed(0.1) : StepControl::adaptive(1e-8, 1e-10), {2.0});
    EXPECT_EQ(r.status, Status::failed) << method;
    EXPECT_NE(r.message.find("event 'e' is not finite"), std::string::npos) << method << ": " << r.message;
    EXPECT_GT(r.t_stop, 1.0 - 1e-9) << method;
    EXPECT_LE(r.t_stop, 2.0) << method;  // the first step end where it is not finite (CVODE may step to the end)
  }
}

}  // namespace
}  // namespace stepwise
