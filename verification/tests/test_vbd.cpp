// Vertex Block Descent (solvers/vertex_block_descent.hpp, the vbd method): its colours share no term, its per-node
// view of the incremental potential is G's own, a sweep never raises G (on the flag and on a scrambled start), its
// answer does not depend on the thread count (and its cpu_seconds counts every thread), with enough sweeps its step
// is backward Euler's, and Chebyshev's
// acceleration of the sweeps keeps G from rising and gains what the sweeps' rate says it should. In the plane too: on pendulum-cartesian's compliant rod (a mass-spring
// system of dimension 2) the node's view is G's, vbd's and xpbd's converged steps are Newton's, and every solver of
// backward Euler's step converges at first order to the rod's true motion.
#include "models/model.hpp"
#include "run/measure.hpp"
#include "solvers/incremental_potential.hpp"
#include "solvers/run_support.hpp"
#include "solvers/method_table.hpp"
#include "solvers/vertex_block_descent.hpp"
#include "verification/convergence.hpp"
#include "verification/tolerances.hpp"
#include "verification/vbd_roundoff.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>

namespace stepwise {
namespace {

// the gusting flag (springs or the continuum), `side` nodes a side, after `frames` backward Euler steps of 1/60 s from
// its flat start: stretched, bent and moving
struct Flag {
  std::unique_ptr<Model> model;
  Eigen::VectorXd y;
};
Flag flag(double continuum, int side, int frames) {
  Flag f{make_model("cloth", {{"continuum", continuum}, {"rows", side}, {"columns", side}}), {}};
  f.y = f.model->initial_state();
  if (frames > 0) {
    const Measured m = run_and_measure(*f.model, "implicit-euler-newton", StepControl::fixed(1.0 / 60), frames / 60.0, frames / 60.0);
    EXPECT_EQ(m.result.status, Status::ok) << m.result.message;
    f.y = m.result.y_stop;
  }
  return f;
}

// one step's potential at h from y
struct Step {
  Stats stats;
  CountedSystem system;
  IncrementalPotential potential;
  Step(const Model& model, const Eigen::VectorXd& y, double h) : system(model, stats), potential(system, *system.as<MassSpringView>()) {
    potential.start(0, y, h);
  }
  std::vector<std::vector<int>> colours() {
    Eigen::SparseMatrix<double> k, d;
    system.as<MassSpringView>()->force_jacobians(0, Eigen::VectorXd::Zero(system.size()), true, k, d);
    return colour_nodes(k, system.as<MassSpringView>()->dimension);
  }
  // vbd's view of the nodes: a network of springs laid out node by node (through_vertex: read through G's vertex)
  VbdNodes nodes(bool through_vertex = false) {
    const auto* network = system.as<SpringNetworkView>();
    return VbdNodes(potential, colours(), network && !through_vertex ? network->network : nullptr);
  }
};

TEST(Vbd, NoTwoNodesOfAColourShareATerm) {
  for (const double continuum : {0.0, 1.0}) {
    const Flag f = flag(continuum, 8, 0);
    Step step(*f.model, f.y, 1.0 / 60);
    const auto colours = step.colours();
    std::vector<int> colour_of(static_cast<size_t>(step.system.size() / 6), -1);
    for (size_t c = 0; c < colours.size(); ++c)
      for (const int i : colours[c]) colour_of[static_cast<size_t>(i)] = static_cast<int>(c);
    for (const int c : colour_of) ASSERT_GE(c, 0);
    // two nodes share a term exactly where moving one changes the other's elastic force: read from vertex_elastic
    const MassSpringView& view = *step.system.as<MassSpringView>();
    const Eigen::VectorXd x = f.y.head(f.y.size() / 2);
    for (int i = 0; i < view.nodes; ++i) {
      Eigen::VectorXd moved = x;
      moved.segment<3>(3 * i) += Eigen::Vector3d(0.01, -0.02, 0.015);
      for (int j = 0; j < view.nodes; ++j) {
        if (j == i || colour_of[static_cast<size_t>(j)] != colour_of[static_cast<size_t>(i)]) continue;
        VertexElastic before, after;
        view.vertex_elastic(j, x, true, true, before);
        view.vertex_elastic(j, moved, true, true, after);
        EXPECT_EQ(before.force, after.force) << "continuum " << continuum << ": nodes " << i << " and " << j << " share a colour and a term";
      }
    }
    std::cout << "continuum " << continuum << ": " << colours.size() << " colours\n";
  }
}

TEST(Vbd, EachNodesViewIsTheIncrementalPotentialsOwn) {
  // G as a function of node i alone: its change is G's change, its gradient G's gradient at the node, its Hessian
  // (exact) h^-2 times the step matrix's diagonal block
  for (const double continuum : {0.0, 1.0}) {
    const Flag f = flag(continuum, 8, 6);
    const double h = 1.0 / 30;
    Step step(*f.model, f.y, h);
    const IncrementalPotential& G = step.potential;
    const Eigen::VectorXd x = G.inertial();
    Eigen::VectorXd gradient;
    G.gradient(x, gradient);
    Eigen::SparseMatrix<double> a;
    G.scaled_hessian(x, false, a);
    const Eigen::MatrixXd A(a);
    const double g_scale = gradient.lpNorm<Eigen::Infinity>(), a_scale = A.lpNorm<Eigen::Infinity>() / (h * h);
    for (const int i : {0, 17, 40}) {
      const IncrementalPotential::Vertex v = G.vertex(i, x, false, true);
      EXPECT_LT((v.gradient - gradient.segment<3>(3 * i)).lpNorm<Eigen::Infinity>(), tolerance::element_roundoff * g_scale) << continuum << " node " << i;
      EXPECT_LT((v.hessian - A.block<3, 3>(3 * i, 3 * i) / (h * h)).lpNorm<Eigen::Infinity>(), tolerance::element_roundoff * a_scale) << continuum << " node " << i;
      Eigen::VectorXd moved = x;
      const Eigen::Vector3d d(1e-3, -2e-3, 5e-4);
      moved.segment<3>(3 * i) += d;
      const double local = G.vertex(i, moved, false, false).value - v.value;
      Eigen::VectorXd dx = Eigen::VectorXd::Zero(x.size());
      dx.segment<3>(3 * i) = d;
      const double global = G.change(x, dx);
      EXPECT_NEAR(local, global, tolerance::potential_roundoff * (std::abs(G.value(x)) + std::abs(global))) << continuum << " node " << i;
      // and as the sweep's line search reads it: the quadratic terms from the node's derivatives, the elastic ones' energies
      EXPECT_NEAR(G.vertex_change(i, moved, v, d), global, tolerance::potential_roundoff * (std::abs(G.value(x)) + std::abs(global))) << continuum << " node " << i;
    }
  }
}

TEST(Vbd, ASweepNeverRaisesTheIncrementalPotential) {
  // the flag at 1/30 s, and the paper's scrambled start (every node placed at random in a cube the sheet's size)
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-0.75, 0.75);
  for (const double continuum : {0.0, 1.0})
    for (const bool scrambled : {false, true}) {
      const Flag f = flag(continuum, 16, scrambled ? 0 : 6);
      Eigen::VectorXd y = f.y;
      if (scrambled) {
        for (Eigen::Index i = 0; i < y.size() / 2; ++i) y[i] = u(rng);
        y.tail(y.size() / 2).setZero();
      }
      Step step(*f.model, y, 1.0 / 30);
      const VbdNodes nodes = step.nodes();
      Eigen::VectorXd x = step.potential.inertial(), decrease;
      double G = step.potential.value(x);
      for (int sweep = 0; sweep < 20; ++sweep) {
        const double reported = vbd_sweep(nodes, x, 1, decrease);
        const double after = step.potential.value(x);
        EXPECT_LE(after, G + tolerance::potential_roundoff * std::abs(G)) << "continuum " << continuum << (scrambled ? ", scrambled" : "") << ", sweep " << sweep;
        EXPECT_NEAR(G - after, reported, tolerance::potential_roundoff * std::abs(G) * nodes.colours().size()) << continuum << " sweep " << sweep;
        G = after;
      }
    }
}

TEST(Vbd, ANetworkOfSpringsLaidOutNodeByNodeSweepsAsGsOwnViewOfTheNodes) {
  // the sweep's layout of a network of springs (each node's springs and blocks of D0 in sweep order) against the same
  // sweeps read through G's view of each node (IncrementalPotential::vertex): the same moves but for round-off, each
  // sweep's within twice vbd_float64_step of the other's, on the flag and on the compliant rod in the plane
  const auto rod = make_model("pendulum-cartesian", {{"compliance", 1e-6}});
  const Flag f = flag(0.0, 16, 6);
  for (const bool plane : {false, true}) {
    const Model& model = plane ? *rod : *f.model;
    Step step(model, plane ? rod->initial_state() : f.y, 1.0 / 30);
    ASSERT_NE(step.system.as<SpringNetworkView>(), nullptr);
    const VbdNodes laid_out = step.nodes(), through_vertex = step.nodes(true);
    Eigen::VectorXd a = step.potential.inertial(), b = a, decrease;
    for (int sweep = 1; sweep <= 5; ++sweep) {
      const double fell_a = vbd_sweep(laid_out, a, 1, decrease), fell_b = vbd_sweep(through_vertex, b, 1, decrease);
      const MassSpringView& view = *step.system.as<MassSpringView>();
      const double bound = 2 * sweep * tolerance::vbd_float64_step(step.potential.h(), *std::min_element(view.mass.begin(), view.mass.end()),
                                                                   gradient_scale(step.potential, view, a));
      EXPECT_LE((a - b).norm(), bound) << (plane ? "rod" : "flag") << ", sweep " << sweep;
      EXPECT_NEAR(fell_a, fell_b, tolerance::potential_roundoff * std::abs(step.potential.value(a))) << (plane ? "rod" : "flag") << ", sweep " << sweep;
      if (sweep == 1) {
        EXPECT_GT(fell_a, 0) << (plane ? "rod" : "flag");
      }
    }
  }
}

TEST(Vbd, TheAnswerDoesNotDependOnTheThreadCount) {
  for (const double continuum : {0.0, 1.0}) {
    const auto model = make_model("cloth", {{"continuum", continuum}, {"rows", 16}, {"columns", 16}});
    std::vector<Eigen::VectorXd> ends;
    for (const int threads : {1, 2, 3}) {
      StepControl control = StepControl::fixed(1.0 / 60);
      control.settings["iterations"] = 5;
      control.settings["threads"] = threads;
      const Measured m = run_and_measure(*model, "vbd", control, 0.1, 0.1);
      ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
      ends.push_back(m.result.y_stop);
    }
    for (size_t k = 1; k < ends.size(); ++k) EXPECT_TRUE(ends[k] == ends[0]) << "continuum " << continuum << ", " << k + 1 << " threads";
  }
}

// a run's cost is every thread's it runs: vbd on 2 threads sweeps the same nodes as on 1, and its cpu_seconds (each
// the least of 3 runs) says so, the workers' CPU time added to the calling thread's
TEST(Vbd, ItsCpuSecondsCountEveryThreadItRuns) {
  const auto model = make_model("cloth", {{"rows", 32}, {"columns", 32}});
  std::array<double, 2> cpu{};
  for (const int threads : {1, 2}) {
    StepControl control = StepControl::fixed(1.0 / 60);
    control.settings["iterations"] = 20;
    control.settings["threads"] = threads;
    const Measured m = least_of_runs(*model, "vbd", control, 0.25, 3);
    ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
    cpu[static_cast<size_t>(threads - 1)] = m.result.stats.cpu_seconds;
  }
  std::cout << "vbd cpu_seconds on 1 and 2 threads: " << cpu[0] << ", " << cpu[1] << " s\n";
  EXPECT_GE(cpu[1], tolerance::worker_cpu_share * cpu[0]);
}

TEST(Vbd, WithEnoughSweepsItsStepIsBackwardEulers) {
  // one 1/60 s step of the 8 x 8 flag in motion: vbd's sweeps, plain and accelerated, against Newton on the same G to
  // 1e-9 m/s (the accelerated sweeps from the start each time, their count doubled)
  for (const double continuum : {0.0, 1.0}) {
    const Flag f = flag(continuum, 8, 6);
    const double h = 1.0 / 60;
    Step step(*f.model, f.y, h);
    Eigen::VectorXd newton_x = step.potential.inertial();
    PotentialNewton newton(NewtonOnPotential{.velocity_tolerance = 1e-9});
    ASSERT_EQ(newton.minimise(step.potential, newton_x, step.stats), "");
    const VbdNodes nodes = step.nodes();
    for (const bool chebyshev : {false, true}) {
      Eigen::VectorXd x, decrease;
      int sweeps = 0;
      double gap = std::numeric_limits<double>::infinity();
      for (int next = 1; next <= 8192 && gap > NewtonOnPotential{}.velocity_tolerance; next = chebyshev ? 2 * next : next + 1) {
        if (chebyshev || sweeps == 0) x = step.potential.inertial();
        vbd_iterate(nodes, x, {.sweeps = chebyshev ? next : 1, .rho = chebyshev ? find_method("vbd-chebyshev")->option("rho")->fallback : 0.0}, decrease);
        sweeps = next;
        gap = (x - newton_x).lpNorm<Eigen::Infinity>() / h;
      }
      std::cout << "continuum " << continuum << (chebyshev ? ", Chebyshev" : "") << ": within " << gap << " m/s of Newton's step after " << sweeps << " sweeps\n";
      EXPECT_LE(gap, NewtonOnPotential{}.velocity_tolerance) << "continuum " << continuum << (chebyshev ? ", Chebyshev" : "");
    }
  }
}

TEST(Vbd, ChebyshevsExtrapolationNeverRaisesTheIncrementalPotential) {
  // G after k accelerated sweeps from the inertial start, k = 1..24: never higher for a larger k (a sweep never raises
  // G, and an extrapolation is taken only where it lowers it); printed beside the plain sweeps' gap to G*
  for (const double continuum : {0.0, 1.0}) {
    const Flag f = flag(continuum, 16, 6);
    Step step(*f.model, f.y, 1.0 / 60);
    const VbdNodes nodes = step.nodes();
    Eigen::VectorXd plain = step.potential.inertial(), decrease, best = plain;
    PotentialNewton newton(NewtonOnPotential{.velocity_tolerance = 1e-9});
    ASSERT_EQ(newton.minimise(step.potential, best, step.stats), "");
    const double least = step.potential.value(best), rho = find_method("vbd-chebyshev")->option("rho")->fallback;
    double last = std::numeric_limits<double>::infinity();
    for (int k = 1; k <= 24; ++k) {
      Eigen::VectorXd x = step.potential.inertial();
      vbd_iterate(nodes, x, {.sweeps = k, .rho = rho}, decrease);
      vbd_sweep(nodes, plain, 1, decrease);
      const double G = step.potential.value(x);
      EXPECT_LE(G, last + tolerance::potential_roundoff * std::abs(G)) << "continuum " << continuum << ", " << k << " sweeps";
      if (k % 4 == 0)
        std::cout << "continuum " << continuum << ", " << k << " sweeps: G - G* plain " << step.potential.value(plain) - least << ", Chebyshev (rho " << rho << ") " << G - least << "\n";
      last = G;
    }
  }
}

TEST(Vbd, InThePlaneOnTheCompliantPendulumItsStepIsBackwardEulersAndXpbds) {
  // the pendulum on a stiff rod (compliance 1e-6 m/N: omega h = 17 at 1/60 s) swinging through 0.5 rad: node 0's view
  // is G's (value, gradient and Hessian, z held at zero), vbd's sweeps reach Newton's step on G, and so does xpbd's
  // projection (XPBD's compliant constraint is backward Euler on the rod's energy, Macklin et al. 2016; for one rod
  // from a fixed pivot its iterations stay on the ray from the pivot through the inertial point, where the step lies)
  const auto model = make_model("pendulum-cartesian", {{"compliance", 1e-6}, {"theta0", 0.5}, {"omega0", 2.0}});
  const MassSpringView& view = *model->as<MassSpringView>();
  ASSERT_EQ(view.dimension, 2);
  const double h = 1.0 / 60;
  const Eigen::VectorXd y = model->initial_state();
  Step step(*model, y, h);
  const IncrementalPotential& G = step.potential;
  Eigen::VectorXd x = G.inertial(), gradient;
  x *= 1.001;  // off the rod's rest length: the spring stretched
  G.gradient(x, gradient);
  Eigen::SparseMatrix<double> a;
  G.scaled_hessian(x, false, a);
  const IncrementalPotential::Vertex v = G.vertex(0, x, false, true);
  const double g_scale = gradient.lpNorm<Eigen::Infinity>(), a_scale = Eigen::MatrixXd(a).lpNorm<Eigen::Infinity>() / (h * h);
  EXPECT_LT((v.gradient.head<2>() - gradient).lpNorm<Eigen::Infinity>(), tolerance::element_roundoff * g_scale);
  EXPECT_EQ(v.gradient[2], 0.0);
  EXPECT_LT((v.hessian.topLeftCorner<2, 2>() - Eigen::MatrixXd(a) / (h * h)).lpNorm<Eigen::Infinity>(), tolerance::element_roundoff * a_scale);
  const Eigen::Vector2d d(1e-4, -2e-4);
  EXPECT_NEAR(G.vertex(0, x + d, false, false).value - v.value, G.change(x, d), tolerance::potential_roundoff * (std::abs(G.value(x)) + 1));

  Eigen::VectorXd newton_x = G.inertial();
  PotentialNewton newton(NewtonOnPotential{.velocity_tolerance = 1e-9});
  ASSERT_EQ(newton.minimise(G, newton_x, step.stats), "");
  const double tolerance = NewtonOnPotential{}.velocity_tolerance;
  Eigen::VectorXd swept = G.inertial(), decrease;
  int sweeps = 0;
  const VbdNodes nodes = step.nodes();
  for (; sweeps < 50 && (swept - newton_x).lpNorm<Eigen::Infinity>() / h > tolerance; ++sweeps) vbd_sweep(nodes, swept, 1, decrease);
  std::cout << "the compliant pendulum: vbd within " << (swept - newton_x).lpNorm<Eigen::Infinity>() / h << " m/s of Newton's step after " << sweeps << " sweeps\n";
  EXPECT_LE((swept - newton_x).lpNorm<Eigen::Infinity>() / h, tolerance);
  for (const char* method : {"vbd", "xpbd"}) {
    StepControl control = StepControl::fixed(h);
    control.settings["iterations"] = 20;
    const Measured m = run_and_measure(*model, method, control, h, h);
    ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
    EXPECT_LE((m.result.y_stop.head<2>() - newton_x).lpNorm<Eigen::Infinity>() / h, tolerance) << method;
    EXPECT_LE((m.result.y_stop.tail<2>() - (newton_x - y.head<2>()) / h).lpNorm<Eigen::Infinity>(), tolerance) << method;
  }
}

TEST(Vbd, OnTheCompliantPendulumItConvergesAtFirstOrderAsEverySolverOfBackwardEulerDoes) {
  // the pendulum on a rod of 1e-2 m/N (omega = 10 rad/s), 1 s from theta0 = 1: vbd (4 sweeps a step), its accelerated
  // twin, backward Euler's Newton, fast mass-spring and xpbd (whose compliant constraint is backward Euler on the
  // rod) each converge at first order to the rod's true motion (verner98 at rtol 1e-12), over six halvings from
  // 1/256 of the rod's period scale 1/omega, where backward Euler's damping of the rod's vibration, omega^2 h t / 2
  // a run, is still linear in h
  const auto model = make_model("pendulum-cartesian", {{"compliance", 1e-2}, {"theta0", 1.0}});
  const double t_end = 1.0, time_scale = 0.1;
  const Measured reference = run_and_measure(*model, "verner98", StepControl::adaptive(1e-12, 1e-14), t_end, t_end);
  ASSERT_EQ(reference.result.status, Status::ok) << reference.result.message;
  for (const char* name : {"vbd", "vbd-chebyshev", "implicit-euler-newton", "fast-mass-spring", "xpbd"}) {
    const Method& method = *find_method(name);
    const ConvergenceSweep sweep = convergence_sweep(*model, method, t_end, 6, coarse_dt(method, time_scale), &reference.result.y_stop);
    ASSERT_GE(sweep.fit_dt.size(), 5u) << name;
    std::cout << "the compliant pendulum, " << name << ": observed order " << sweep.observed_order << ", error " << sweep.fit_error.front() << " -> "
              << sweep.fit_error.back() << "\n";
    EXPECT_NEAR(sweep.observed_order, 1.0, tolerance::order_band) << name;
  }
}

// |x|, weighted by the nodes' masses: the norm the sweeps' error decays in
double mass_norm(const IncrementalPotential& G, const Eigen::VectorXd& x) { return std::sqrt(x.cwiseAbs2().dot(G.mass())); }

TEST(Vbd, ChebyshevsAccelerationIsWhatTheSweepsRateGives) {
  // Chebyshev's semi-iteration on an iteration of rate rho: after k sweeps its error is at most 2 r^k / (1 + r^2k) of the
  // start's, r = rho / (1 + sqrt(1 - rho^2)), where plain sweeps leave rho^k (Golub & Varga 1961; Wang 2015 takes the
  // weights for Gauss-Seidel). The flag's step measured: the plain sweeps' rate read off their error's late decay, the
  // accelerated sweeps at that rate, their error after k sweeps against the theory's gain
  for (const double continuum : {0.0, 1.0}) {
    const Flag f = flag(continuum, 16, 6);
    Step step(*f.model, f.y, 1.0 / 60);
    const VbdNodes nodes = step.nodes();
    Eigen::VectorXd best = step.potential.inertial(), decrease;
    PotentialNewton newton(NewtonOnPotential{.velocity_tolerance = 1e-12});
    ASSERT_EQ(newton.minimise(step.potential, best, step.stats), "");
    std::vector<double> plain;  // the plain sweeps' error after k sweeps
    Eigen::VectorXd x = step.potential.inertial();
    plain.push_back(mass_norm(step.potential, x - best));
    for (int k = 1; k <= 80; ++k) {
      vbd_sweep(nodes, x, 1, decrease);
      plain.push_back(mass_norm(step.potential, x - best));
    }
    const double rho = std::pow(plain[80] / plain[60], 1.0 / 20);
    const double r = rho / (1 + std::sqrt(1 - rho * rho));
    for (const int k : {10, 20, 40}) {
      Eigen::VectorXd accelerated = step.potential.inertial();
      vbd_iterate(nodes, accelerated, {.sweeps = k, .rho = rho}, decrease);
      const double chebyshev = mass_norm(step.potential, accelerated - best);
      const double gain = plain[static_cast<size_t>(k)] / chebyshev, theory = std::pow(rho, k) / (2 * std::pow(r, k) / (1 + std::pow(r, 2 * k)));
      std::cout << "continuum " << continuum << ": rho " << rho << ", after " << k << " sweeps plain " << plain[static_cast<size_t>(k)] / plain[0]
                << ", Chebyshev " << chebyshev / plain[0] << ": gain " << gain << ", theory's " << theory << "\n";
      EXPECT_GE(std::log(gain), tolerance::chebyshev_gain_share * std::log(theory)) << "continuum " << continuum << ", " << k << " sweeps";
    }
  }
}

}  // namespace
}  // namespace stepwise
