// The constrained methods on the Cartesian pendulum: position-based dynamics (pbd, xpbd), the claims of Müller et
// al. (2007) and Macklin, Müller & Chentanez (2016) that their use rests on, and RATTLE's (Hairer, Lubich &
// Wanner, VII.1): second order, symplectic, on the manifold. Each measured.
#include "models/model.hpp"
#include "run/measure.hpp"
#include "run/projected_model.hpp"
#include "solvers/capabilities/distance_constraints.hpp"
#include "solvers/method_table.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace stepwise;

namespace {

std::unique_ptr<Model> cartesian(double theta0, double compliance, double mass = 1.0) {
  return make_model("pendulum-cartesian", {{"theta0", theta0}, {"compliance", compliance}, {"mass", mass}});
}

StepControl frames(double dt, int substeps, int iterations) {
  StepControl c = StepControl::fixed(dt);
  c.settings["substeps"] = substeps;
  c.settings["iterations"] = iterations;
  return c;
}

RunResult solve(const Model& model, const char* method, const StepControl& control, const Eigen::VectorXd& y0, const std::vector<double>& t_out) {
  return make_integrator(method, control)->solve(model, 0.0, y0, t_out);
}

}  // namespace

// one sweep of one iteration puts a point held by an inextensible rod back on its circle, whatever it started
// from: the projection is exact, to rounding
TEST(PositionBased, OneIterationWithZeroComplianceSatisfiesTheConstraintToRoundOff) {
  const auto model = cartesian(1.0, 0.0);
  for (const char* method : {"xpbd", "pbd"})
    for (const double speed : {0.0, 3.0, 30.0}) {
      Eigen::VectorXd y0 = model->initial_state();
      y0.tail<2>() << speed, -0.5 * speed;  // off the circle's tangent: the free step leaves the circle
      const RunResult r = solve(*model, method, frames(0.01, 1, 1), y0, {0.01});
      ASSERT_EQ(r.status, Status::ok) << method;
      EXPECT_LE(std::abs(r.y_stop.head<2>().norm() - 1.0), tolerance::projection_roundoff) << method << " at speed " << speed;
    }
}

// Hooke's law whatever the solver's settings: xpbd's hanging mass rests at the static stretch m g alpha for any
// substeps and iterations; pbd's rest length moves with the iterations (its compliance is a per-iteration
// stiffness), and with one iteration the two methods are the same
TEST(PositionBased, XpbdHangsAtTheStaticStretchMgAlphaAtAnySettingsAndPbdDoesNot) {
  const double alpha = 1e-3, mass = 2.0, g = 9.81, stretch = mass * g * alpha;
  const auto model = cartesian(0.0, alpha, mass);
  Eigen::VectorXd y0(4);
  y0 << 0, -(1.0 + stretch), 0, 0;
  std::vector<double> t_out;
  for (int k = 1; k <= 50; ++k) t_out.push_back(0.02 * k);
  for (const auto& [substeps, iterations] : {std::pair{1, 1}, {1, 4}, {10, 1}, {4, 10}}) {
    const StepControl control = frames(1e-3, substeps, iterations);
    const RunResult x = solve(*model, "xpbd", control, y0, t_out), p = solve(*model, "pbd", control, y0, t_out);
    ASSERT_EQ(x.status, Status::ok);
    ASSERT_EQ(p.status, Status::ok);
    double xpbd_off = 0, pbd_off = 0;
    for (const auto& y : x.trajectory.y) xpbd_off = std::max(xpbd_off, std::abs(y.head<2>().norm() - (1.0 + stretch)));
    for (const auto& y : p.trajectory.y) pbd_off = std::max(pbd_off, std::abs(y.head<2>().norm() - (1.0 + stretch)));
    const double substeps_run = 1000.0 * substeps;  // 1 s of 1 ms frames
    EXPECT_LE(xpbd_off, substeps_run * tolerance::projection_roundoff) << substeps << " substeps, " << iterations << " iterations";
    // one iteration from lambda = 0 is the same update in both; from the second on, pbd pulls the whole way again
    if (iterations == 1) EXPECT_EQ(p.y_stop, x.y_stop) << substeps << " substeps";
    else EXPECT_GT(pbd_off, tolerance::pbd_stretch_differs * stretch) << substeps << " substeps, " << iterations << " iterations";
  }
}

// "small steps": xpbd with one iteration a substep converges to the reduced pendulum at first order in the
// substep, with the constraint held at round-off throughout
TEST(PositionBased, XpbdSmallStepsConvergeAtFirstOrderToTheReducedPendulum) {
  const auto model = cartesian(1.0, 0.0);
  std::vector<double> log_h, log_error;
  for (const int substeps : {4, 8, 16, 32, 64}) {
    const StepControl control = frames(0.01, substeps, 1);
    const Measured m = run_and_measure(*model, "xpbd", control, 1.0, 0.01);
    ASSERT_EQ(m.result.status, Status::ok);
    ASSERT_TRUE(m.error);
    log_h.push_back(std::log(0.01 / substeps));
    log_error.push_back(std::log(*m.error));
    for (const auto& y : m.result.trajectory.y)
      EXPECT_LE(std::abs(y.head<2>().norm() - 1.0), 100 * substeps * tolerance::projection_roundoff);
  }
  // least-squares slope of log error against log h
  const double n = static_cast<double>(log_h.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < log_h.size(); ++i) sx += log_h[i], sy += log_error[i], sxx += log_h[i] * log_h[i], sxy += log_h[i] * log_error[i];
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  EXPECT_NEAR(slope, 1.0, tolerance::order_band);
}

// the same pendulum through an ODE method: the constrained equations of motion reach the reduced pendulum's
// answer (rk4 at its fourth order), and drift from the constraint by the method's error, not at round-off
TEST(PositionBased, TheCartesianPendulumOnAnOdeMethodIsTheReducedPendulum) {
  const auto model = cartesian(1.0, 0.0);
  const Measured coarse = run_and_measure(*model, "rk4", StepControl::fixed(0.01), 1.0, 0.01);
  const Measured fine = run_and_measure(*model, "rk4", StepControl::fixed(0.005), 1.0, 0.01);
  ASSERT_TRUE(coarse.error && fine.error);
  EXPECT_NEAR(std::log2(*coarse.error / *fine.error), 4.0, 4 * tolerance::order_band);  // two points: a wider band
  const auto* constraints = model->as<DistanceConstraints>();
  ASSERT_NE(constraints, nullptr);
  EXPECT_GT(constraints->drift(coarse.result.y_stop.data()), 0.0);
}

// RATTLE: second order to the reduced pendulum, the rod held to rounding at every sample
TEST(Rattle, ConvergesAtSecondOrderOnTheManifold) {
  const auto model = cartesian(1.0, 0.0);
  std::vector<double> errors;
  for (const double dt : {0.02, 0.01, 0.005, 0.0025}) {
    const Measured m = run_and_measure(*model, "rattle", StepControl::fixed(dt), 1.0, 0.04);  // outputs on every step grid
    ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
    ASSERT_TRUE(m.error);
    errors.push_back(*m.error);
    for (const auto& y : m.result.trajectory.y) EXPECT_LE(std::abs(y.head<2>().norm() - 1.0), 3 * tolerance::shake_converged);  // L + 2 |x|
  }
  for (size_t k = 1; k < errors.size(); ++k) EXPECT_NEAR(std::log2(errors[k - 1] / errors[k]), 2.0, tolerance::order_band) << k;
}

// symplectic: over 10^4 periods the energy error oscillates without drifting (its largest over the last hundred
// periods no larger than over the first hundred, within the bounded error's own spread), and the rod stays at its
// length to rounding
TEST(Rattle, KeepsTheEnergyBoundedOverTenThousandPeriods) {
  const auto model = cartesian(1.0, 0.0);
  const double period = 2.1555, t_end = 1e4 * period;  // the pendulum at theta0 = 1 rad: 4 K(sin 1/2) / sqrt(g/L)
  const Measured m = run_and_measure(*model, "rattle", StepControl::fixed(0.01), t_end, period / 7);
  ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
  const auto& ys = m.result.trajectory.y;
  const double e0 = *model->energy(model->initial_state());
  const size_t window = ys.size() / 100;
  double first = 0, last = 0, off = 0;
  for (size_t k = 0; k < ys.size(); ++k) {
    const double error = std::abs(*model->energy(ys[k]) - e0);
    if (k < window) first = std::max(first, error);
    if (k >= ys.size() - window) last = std::max(last, error);
    off = std::max(off, std::abs(ys[k].head<2>().norm() - 1.0));
  }
  EXPECT_GT(first, 0.0);
  EXPECT_LE(last, 2 * first);
  EXPECT_LE(off, 3 * tolerance::shake_converged);  // L + 2 |x|
}

// a compliant constraint is a spring in RATTLE's kicks (Störmer-Verlet on it), not a rod to meet: on the Cartesian
// pendulum with a rod of compliance 1e-3 m/N it converges at second order to the spring pendulum's answer (verner98
// at rtol 1e-11 on the model's own equations), where meeting |x| = L would leave an error of the stretch's size
TEST(Rattle, StepsACompliantConstraintAsASpringAtSecondOrder) {
  const auto spring = cartesian(1.0, 1e-3);
  const Measured reference = run_and_measure(*spring, "verner98", StepControl::adaptive(1e-11, 1e-13), 1.0, 1.0);
  ASSERT_EQ(reference.result.status, Status::ok);
  std::vector<double> errors;
  for (const double dt : {2e-4, 1e-4, 5e-5}) {
    const Measured m = run_and_measure(*spring, "rattle", StepControl::fixed(dt), 1.0, 1.0);
    ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
    errors.push_back(max_norm_error(m.result.y_stop, reference.result.y_stop));
  }
  for (size_t k = 1; k < errors.size(); ++k) EXPECT_NEAR(std::log2(errors[k - 1] / errors[k]), 2.0, tolerance::order_band) << k;
}

// the chain of 20 links released from the horizontal has no closed form: its reference at t = 1 s is verner98 on
// its constrained equations at rtol 1e-10, and RATTLE converges to it at second order (so the two agree to the
// digits RATTLE's finest step reaches, and each run keeps its links at their length to rounding)
TEST(Rattle, TheChainsReferenceIsConvergedTwoWays) {
  const auto chain = make_model("chain", {});
  const Measured reference = run_and_measure(*chain, "verner98", StepControl::adaptive(1e-10, 1e-12), 1.0, 0.25);
  ASSERT_EQ(reference.result.status, Status::ok) << reference.result.message;
  const auto* constraints = chain->as<DistanceConstraints>();
  ASSERT_NE(constraints, nullptr);
  std::vector<double> errors;
  for (const double dt : {1e-3, 5e-4, 2.5e-4}) {
    const Measured m = run_and_measure(*chain, "rattle", StepControl::fixed(dt), 1.0, 0.25);
    ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
    errors.push_back((m.result.y_stop - reference.result.y_stop).cwiseAbs().maxCoeff());
    EXPECT_LE(constraints->drift(m.result.y_stop.data()), tolerance::chain_link_roundoff);
  }
  for (size_t k = 1; k < errors.size(); ++k) EXPECT_NEAR(std::log2(errors[k - 1] / errors[k]), 2.0, tolerance::order_band) << k;
}

// --constraint project: rk4 on the chain's constrained equations drifts off the links by its own error; the
// same run with the state put back after every step keeps them to rounding, and its answer still converges to the
// reference (the projection moves the state by the step's local error, not more)
TEST(Projection, KeepsAnOdeMethodOnTheChainsConstraints) {
  const auto plain = make_model("chain", {});
  const auto kept = projected(make_model("chain", {}));
  const auto* constraints = plain->as<DistanceConstraints>();
  ASSERT_NE(constraints, nullptr);
  const Measured a = run_and_measure(*plain, "rk4", StepControl::fixed(1e-3), 1.0, 0.01);
  const Measured b = run_and_measure(*kept, "rk4", StepControl::fixed(1e-3), 1.0, 0.01);
  ASSERT_EQ(a.result.status, Status::ok);
  ASSERT_EQ(b.result.status, Status::ok);
  EXPECT_EQ(b.result.stats.projections, 1000);
  double drift_plain = 0, drift_kept = 0;
  for (const auto& y : a.result.trajectory.y) drift_plain = std::max(drift_plain, constraints->drift(y.data()));
  for (const auto& y : b.result.trajectory.y) drift_kept = std::max(drift_kept, constraints->drift(y.data()));
  EXPECT_LE(drift_kept, tolerance::chain_link_roundoff);
  EXPECT_GT(drift_plain, 1e3 * tolerance::chain_link_roundoff);
  const Measured reference = run_and_measure(*plain, "verner98", StepControl::adaptive(1e-10, 1e-12), 1.0, 0.25);
  EXPECT_LE((b.result.y_stop - reference.result.y_stop).cwiseAbs().maxCoeff(), (a.result.y_stop - reference.result.y_stop).cwiseAbs().maxCoeff());
}

// Baumgarte (the chain's baumgarte flag, --constraint baumgarte): the multipliers pull any drift back at the
// critically damped rate w = 10 sqrt(g / l), so a drift that grows like t under plain rk4 stays near the
// error made in 1/w; over 1 s that is ~1/(w t) = 1/140 of the plain drift, asserted with room at a tenth
TEST(Projection, BaumgarteHoldsTheChainsDriftDown) {
  const auto plain = make_model("chain", {});
  const auto pulled = make_model("chain", {{"baumgarte", 1}});
  const auto* constraints = plain->as<DistanceConstraints>();
  const Measured a = run_and_measure(*plain, "rk4", StepControl::fixed(1e-3), 1.0, 0.01);
  const Measured b = run_and_measure(*pulled, "rk4", StepControl::fixed(1e-3), 1.0, 0.01);
  ASSERT_EQ(b.result.status, Status::ok);
  double drift_plain = 0, drift_pulled = 0;
  for (const auto& y : a.result.trajectory.y) drift_plain = std::max(drift_plain, constraints->drift(y.data()));
  for (const auto& y : b.result.trajectory.y) drift_pulled = std::max(drift_pulled, constraints->drift(y.data()));
  EXPECT_LE(drift_pulled, tolerance::baumgarte_drift_share * drift_plain);
}

// IDA on the constrained scenes as DAEs (solvers/methods/ida.cpp): the same variable-order BDF and error control
// as CVODE's on the scenes' ODE form, so its error at t_end (against the reduced pendulum's exact answer, the
// chain's reference) is no worse than CVODE BDF's at the same tolerances and falls as they tighten; the
// constraints, equations of the DAE, are held to the tolerance
TEST(Ida, SolvesTheConstrainedScenesLikeCvodeBdfOnTheirOdeForm) {
  const auto pendulum = cartesian(1.0, 0.0);
  const auto chain = make_model("chain", {});
  const Measured reference = run_and_measure(*chain, "verner98", StepControl::adaptive(1e-10, 1e-12), 1.0, 1.0);
  ASSERT_EQ(reference.result.status, Status::ok);
  const auto* rod = pendulum->as<DistanceConstraints>();
  const auto* links = chain->as<DistanceConstraints>();
  std::vector<double> pendulum_errors, chain_errors;
  for (const double rtol : {1e-6, 1e-9}) {
    const StepControl control = StepControl::adaptive(rtol, rtol);
    const Measured p = run_and_measure(*pendulum, "ida", control, 10.0, 0.1), pb = run_and_measure(*pendulum, "cvode-bdf", control, 10.0, 0.1);
    const Measured c = run_and_measure(*chain, "ida", control, 1.0, 0.05), cb = run_and_measure(*chain, "cvode-bdf", control, 1.0, 0.05);
    for (const Measured* m : {&p, &pb, &c, &cb}) ASSERT_EQ(m->result.status, Status::ok) << m->result.message;
    pendulum_errors.push_back(*p.error);
    chain_errors.push_back(max_norm_error(c.result.y_stop, reference.result.y_stop));
    EXPECT_LE(pendulum_errors.back(), tolerance::bdf_peer_factor * *pb.error) << "rtol " << rtol;
    EXPECT_LE(chain_errors.back(), tolerance::bdf_peer_factor * max_norm_error(cb.result.y_stop, reference.result.y_stop)) << "rtol " << rtol;
    for (const auto& y : p.result.trajectory.y) EXPECT_LE(rod->drift(y.data()), tolerance::adaptive_agreement_factor * rtol) << "rtol " << rtol;
    for (const auto& y : c.result.trajectory.y) EXPECT_LE(links->drift(y.data()), tolerance::adaptive_agreement_factor * rtol) << "rtol " << rtol;
  }
  // 1000 times tighter: at least 1000^(p/(p+1)) smaller for the lowest order, p = 1
  EXPECT_GE(std::log10(pendulum_errors[0] / pendulum_errors[1]) / 3, tolerance::min_tolerance_slope(1));
  EXPECT_GE(std::log10(chain_errors[0] / chain_errors[1]) / 3, tolerance::min_tolerance_slope(1));
}

// compliant constraints in IDA's DAE (alpha > 0: a spring, lambda = -g / alpha, its velocity left free): the spring
// pendulum and a small spring cloth (its springs read as compliant constraints, their Voigt damping off, which the
// constraint methods leave out) are as far from their ODE form run to convergence as CVODE BDF on that ODE is, at the
// same tolerance (the same BDF and error control)
TEST(Ida, CompliantConstraintsAreSpringsAsTheOdeFormHasThem) {
  const double rtol = 1e-8;
  const auto spring_pendulum = cartesian(1.0, 1e-3);
  const auto cloth = make_model("cloth", {{"rows", 4}, {"columns", 4}, {"damping", 0}, {"pin_corners", 0}, {"pin_top_corners", 1}});
  for (const auto& [model, t_end] : {std::pair{spring_pendulum.get(), 2.0}, std::pair{cloth.get(), 0.5}}) {
    const Measured reference = run_and_measure(*model, "verner98", StepControl::adaptive(1e-12, 1e-14), t_end, t_end);
    const Measured m = run_and_measure(*model, "ida", StepControl::adaptive(rtol, rtol), t_end, t_end);
    const Measured peer = run_and_measure(*model, "cvode-bdf", StepControl::adaptive(rtol, rtol), t_end, t_end);
    for (const Measured* r : {&reference, &m, &peer}) ASSERT_EQ(r->result.status, Status::ok) << r->result.message;
    const double error = max_norm_error(m.result.y_stop, reference.result.y_stop), peer_error = max_norm_error(peer.result.y_stop, reference.result.y_stop);
    std::cout << model->name() << ": ida at rtol " << rtol << " off the converged ODE by " << error << ", cvode-bdf by " << peer_error << "\n";
    EXPECT_LE(error, tolerance::bdf_peer_factor * peer_error) << model->name();
  }
}

// a scene without constraints refuses the constrained methods, naming what they need
TEST(PositionBased, AModelWithoutConstraintsIsRefused) {
  const auto pendulum = make_model("pendulum", {});
  for (const char* name : {"pbd", "xpbd", "rattle", "ida"}) {
    const Method& method = *find_method(name);
    EXPECT_FALSE(method_applies(method, *pendulum));
    EXPECT_NE(method_requirement(method, *pendulum).find("distance constraints"), std::string::npos);
  }
}
