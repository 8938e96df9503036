// Mass-spring systems (the cloth's first pieces): Voigt springs' internal forces keep momentum, their
// analytic sparse Jacobian against central differences (springs stretched and compressed), and the
// springs in the plane the same as in space with z zero, the
// hanging chain settling into its exact static equilibrium under implicit Euler and CVODE BDF with KLU.
#include "models/hanging_chain.hpp"
#include "models/model.hpp"
#include "models/springs.hpp"
#include "solvers/method_table.hpp"
#include "solvers/incremental_potential.hpp"
#include "solvers/mass_spring_implicit.hpp"
#include "solvers/run_support.hpp"
#include "solvers/stability.hpp"
#include "run/measure.hpp"
#include "verification/order_fit.hpp"
#include "verification/stability.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>
#include <tuple>

namespace stepwise {
namespace {

TEST(Springs, InternalForcesKeepLinearAndAngularMomentum) {
  // 30 nodes joined by 100 random springs, no anchors, some stretched, some compressed, all moving
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  const int nodes = 30;
  Eigen::VectorXd x(3 * nodes), v(3 * nodes), f = Eigen::VectorXd::Zero(3 * nodes);
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    x[i] = u(rng);
    v[i] = u(rng);
  }
  std::vector<Spring> springs;
  for (int s = 0; s < 100; ++s) {
    const int a = static_cast<int>(rng() % nodes), b = (a + 1 + static_cast<int>(rng() % (nodes - 1))) % nodes;
    springs.push_back(Spring{a, b, 1 + u(rng) * 0.9, 100 * (1.5 + u(rng)), 1.5 + u(rng)});
  }
  add_spring_forces(springs, x.data(), v.data(), f.data());
  Eigen::Vector3d total = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero();
  for (int i = 0; i < nodes; ++i) {
    total += f.segment<3>(3 * i);
    moment += x.segment<3>(3 * i).cross(f.segment<3>(3 * i));
  }
  const double scale = f.lpNorm<Eigen::Infinity>() * static_cast<double>(springs.size());
  EXPECT_LT(total.norm(), tolerance::spring_momentum_roundoff * scale);
  EXPECT_LT(moment.norm(), tolerance::spring_momentum_roundoff * scale);
}

TEST(Springs, TheChainsSparseJacobianMatchesCentralDifferences) {
  const auto model = make_model("hanging-chain", {{"nodes", 6}, {"drag", 0.3}, {"damping", 1.5}});
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const double spread : {0.01, 0.08}) {  // springs near rest length, and some compressed to 20%
    Eigen::VectorXd y = model->initial_state();
    for (Eigen::Index i = 0; i < y.size(); ++i) y[i] += (i < y.size() / 2 ? spread : 1.0) * u(rng);
    Eigen::SparseMatrix<double> sparse;
    model->as<SparseJacobian>()->sparse_jacobian(0, y, sparse);
    const Eigen::MatrixXd analytic = Eigen::MatrixXd(sparse);
    // springs 0.1 m long put third derivatives of f at ~c/(m L^2) = 1e5 against |J| ~ 1e3: plain central
    // differences truncate at ~1e-6 of |J| there, so the columns are Richardson-extrapolated from steps h
    // and h/2 (truncation O(h^4)), leaving round-off eps |f| / h
    const auto column = [&](Eigen::Index j, double h) {
      Eigen::VectorXd yp = y, ym = y, fp(y.size()), fm(y.size());
      yp[j] += h;
      ym[j] -= h;
      model->rhs(0, yp, fp);
      model->rhs(0, ym, fm);
      return Eigen::VectorXd((fp - fm) / (2 * h));
    };
    Eigen::MatrixXd fd(y.size(), y.size());
    for (Eigen::Index j = 0; j < y.size(); ++j) fd.col(j) = (4 * column(j, tolerance::richardson_step / 2) - column(j, tolerance::richardson_step)) / 3;
    EXPECT_LT((analytic - fd).lpNorm<Eigen::Infinity>(), tolerance::jacobian_richardson * (1 + analytic.lpNorm<Eigen::Infinity>())) << spread;
  }
}

TEST(Springs, InThePlaneTheyAreTheSpaceSpringsWithZeroZ) {
  // 12 nodes in the plane z = 0 joined by 30 random springs (and 3 pinned to anchors), moving in the plane: the
  // network of dimension 2 (pendulum-cartesian's) gives the energy, forces, Jacobians and per-node terms the network
  // of dimension 3 gives on the same nodes with z = 0, each read at the node's x and y
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  const int nodes = 12;
  std::vector<Spring> springs;
  for (int s = 0; s < 30; ++s) {
    const int a = static_cast<int>(rng() % nodes), b = (a + 1 + static_cast<int>(rng() % (nodes - 1))) % nodes;
    springs.push_back(Spring{a, b, 1 + u(rng) * 0.5, 100 * (1.5 + u(rng)), 1.5 + u(rng)});
  }
  for (int s = 0; s < 3; ++s) springs.push_back(Spring{-1, s, 0.5, 80, 1, Eigen::Vector3d(u(rng), u(rng), 0)});
  std::vector<double> mass(nodes);
  for (double& m : mass) m = 1.5 + u(rng);
  const SpringNetwork plane(mass, springs, 2, 0.3), space(mass, springs, 3, 0.3);
  Eigen::VectorXd y2(4 * nodes), y3 = Eigen::VectorXd::Zero(6 * nodes);
  for (Eigen::Index i = 0; i < y2.size(); ++i) y2[i] = u(rng);
  for (int part = 0; part < 2; ++part)  // x, then v: node k's two coordinates into 3 a node
    for (Eigen::Index i = 0; i < 2 * nodes; ++i) y3[part * 3 * nodes + 3 * (i / 2) + i % 2] = y2[part * 2 * nodes + i];
  const Eigen::VectorXd x2 = y2.head(2 * nodes), x3 = y3.head(3 * nodes);
  std::vector<Eigen::Index> in_plane;  // x's coordinates of 3-D's that are the plane's
  for (Eigen::Index i = 0; i < 3 * nodes; ++i)
    if (i % 3 != 2) in_plane.push_back(i);
  const Eigen::VectorXi kept = Eigen::Map<const Eigen::Matrix<Eigen::Index, Eigen::Dynamic, 1>>(in_plane.data(), 2 * nodes).cast<int>();

  const double energy = space.view().potential(x3);
  EXPECT_NEAR(plane.view().potential(x2), energy, tolerance::element_roundoff * energy);
  Eigen::VectorXd f2 = Eigen::VectorXd::Zero(2 * nodes), f3 = Eigen::VectorXd::Zero(3 * nodes);
  plane.view().elastic_force(x2, f2);
  space.view().elastic_force(x3, f3);
  const double f_scale = f3.lpNorm<Eigen::Infinity>();
  EXPECT_LT((f2 - f3(kept)).lpNorm<Eigen::Infinity>(), tolerance::element_roundoff * f_scale);
  for (const bool definite : {false, true}) {
    Eigen::SparseMatrix<double> k2, d2, k3, d3;
    plane.view().force_jacobians(0, y2, definite, k2, d2);
    space.view().force_jacobians(0, y3, definite, k3, d3);
    const Eigen::MatrixXd K3 = Eigen::MatrixXd(k3)(kept, kept), D3 = Eigen::MatrixXd(d3)(kept, kept);
    EXPECT_LT((Eigen::MatrixXd(k2) - K3).lpNorm<Eigen::Infinity>(), tolerance::element_roundoff * K3.lpNorm<Eigen::Infinity>()) << definite;
    EXPECT_LT((Eigen::MatrixXd(d2) - D3).lpNorm<Eigen::Infinity>(), tolerance::element_roundoff * D3.lpNorm<Eigen::Infinity>()) << definite;
    for (int node = 0; node < nodes; ++node) {
      VertexElastic at2, at3;
      plane.view().vertex_elastic(node, x2, definite, true, at2);
      space.view().vertex_elastic(node, x3, definite, true, at3);
      EXPECT_NEAR(at2.energy, at3.energy, tolerance::element_roundoff * energy) << node;
      EXPECT_LT((at2.force - at3.force).head<2>().lpNorm<Eigen::Infinity>(), tolerance::element_roundoff * f_scale) << node;
      const Eigen::Matrix2d jacobian_gap = (at2.jacobian - at3.jacobian).topLeftCorner<2, 2>();
      EXPECT_LT(jacobian_gap.lpNorm<Eigen::Infinity>(), tolerance::element_roundoff * K3.lpNorm<Eigen::Infinity>()) << node;
    }
  }
}

TEST(HangingChain, SettlesIntoItsExactStaticEquilibrium) {
  const int nodes = 10;
  const double mass = 0.1, stiffness = 100, rest = 0.1, damping = 2, g = 9.81, t_end = 100;
  const auto model = make_model("hanging-chain", {{"nodes", nodes}, {"mass", mass}, {"stiffness", stiffness}, {"rest_length", rest}, {"damping", damping}});
  const std::vector<double> equilibrium = chain_equilibrium(nodes, mass, stiffness, rest, g);
  // it starts at rest length: the bottom node is m g N (N + 1) / (2 c) above its equilibrium
  const double offset = mass * g * nodes * (nodes + 1) / (2 * stiffness);
  EXPECT_NEAR(model->initial_state()[3 * (nodes - 1) + 1] - equilibrium.back(), offset, tolerance::accumulated_roundoff);
  const double rtol = 1e-8;
  for (const auto& [method, control, own_error] :
       {std::tuple{"implicit-euler", StepControl::fixed(1e-2), 0.0}, std::tuple{"cvode-bdf", StepControl::adaptive(rtol, rtol * 1e-2), 10 * rtol * 2.0}}) {
    const Measured m = run_and_measure(*model, method, control, t_end, t_end);
    ASSERT_EQ(m.result.status, Status::ok) << method << m.result.message;
    double worst = 0;
    for (int k = 0; k < nodes; ++k) worst = std::max(worst, std::abs(m.result.y_stop[3 * k + 1] - equilibrium[static_cast<size_t>(k)]));
    const double left = tolerance::chain_settled(t_end, offset, nodes, mass, stiffness, damping) + own_error + tolerance::accumulated_roundoff;
    EXPECT_LT(worst, left) << method;
    // and at rest: no mode moves faster than the highest frequency, 2 sqrt(c/m), times what is left of it
    EXPECT_LT(m.result.y_stop.tail(3 * nodes).lpNorm<Eigen::Infinity>(), 2 * std::sqrt(stiffness / mass) * left) << method;
    std::cout << method << ": largest height error " << worst << " m after " << t_end << " s (" << m.result.stats.steps << " steps)\n";
  }
}

}  // namespace
}  // namespace stepwise

namespace stepwise {
namespace {

// a small cloth with everything on: one pin, a gusting wind across it, a picked node, drag and damping
std::unique_ptr<Model> small_cloth(Params extra = {}) {
  Params p{{"rows", 4}, {"columns", 5}, {"pin_corners", 0}, {"pin_row", 0}, {"pin_column", 0}, {"wind_x", 1}, {"wind_z", 3},
           {"wind_coefficient", 0.7}, {"gust_amplitude", 0.4}, {"pick_row", 3}, {"pick_column", 2}, {"pick_fy", -0.3}, {"drag", 0.2}, {"damping", 0.05}};
  for (const auto& [k, v] : extra) p[k] = v;
  return make_model("cloth", p);
}

// a state with springs stretched and compressed, moving
Eigen::VectorXd shaken(const Model& model, double spread, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd y = model.initial_state();
  for (Eigen::Index i = 0; i < y.size(); ++i) y[i] += (i < y.size() / 2 ? spread : 1.0) * u(rng);
  return y;
}

TEST(Cloth, ForceJacobiansMatchCentralDifferences) {
  // the spring sheet's, the continuum's (membrane and bending elements on the same grid), and the continuum damped by
  // its own viscous stress (rayleigh_beta)
  for (const double continuum : {0.0, 1.0, 2.0}) {
    const auto model = small_cloth(continuum < 2 ? Params{{"continuum", continuum}} : Params{{"continuum", 1}, {"rayleigh_beta", 1e-3}});
    const MassSpringView& view = *model->as<MassSpringView>();
    const Eigen::Index n = model->size() / 2;
    for (const double spread : {0.02, 0.1}) {  // near rest, and some compressed
      const Eigen::VectorXd y = shaken(*model, spread, 3);
      const double t = 0.3;
      Eigen::SparseMatrix<double> k, d;
      view.force_jacobians(t, y, false, k, d);
      // f = M a, by Richardson-extrapolated central differences (as for the chain)
      const auto force = [&](const Eigen::VectorXd& at) {
        Eigen::VectorXd a(n);
        model->as<SecondOrderView>()->acceleration(t, at, a);
        for (int i = 0; i < view.nodes; ++i) a.segment<3>(3 * i) *= view.mass[i];
        return a;
      };
      const auto column = [&](Eigen::Index j, double h) {
        Eigen::VectorXd yp = y, ym = y;
        yp[j] += h;
        ym[j] -= h;
        return Eigen::VectorXd((force(yp) - force(ym)) / (2 * h));
      };
      // both blocks are differences of the same f, so they share its round-off, eps |f| / h absolute: the
      // scale is the whole Jacobian's, as for the chain
      const double scale = 1 + std::max(Eigen::MatrixXd(k).lpNorm<Eigen::Infinity>(), Eigen::MatrixXd(d).lpNorm<Eigen::Infinity>());
      for (const auto& [offset, analytic, what] : {std::tuple{Eigen::Index{0}, Eigen::MatrixXd(k), "df/dx"}, std::tuple{n, Eigen::MatrixXd(d), "df/dv"}}) {
        Eigen::MatrixXd fd(n, n);
        for (Eigen::Index j = 0; j < n; ++j)
          fd.col(j) = (4 * column(offset + j, tolerance::richardson_step / 2) - column(offset + j, tolerance::richardson_step)) / 3;
        EXPECT_LT((analytic - fd).lpNorm<Eigen::Infinity>(), tolerance::jacobian_richardson * scale) << what << " at spread " << spread << ", continuum " << continuum;
      }
    }
  }
}

TEST(Cloth, BendSpringsResistAFoldAlongEitherAxisAlike) {
  // a square sheet of bend springs alone (no gravity, wind, drag, damping or pins), folded out of its plane into
  // a parabola along the rows, z = a (r - 3)^2, and the same fold along the columns, z = a (c - 3)^2: the grid
  // transposed takes one onto the other ((x, y) -> (-y - w/2, -x - w/2), z kept), so node (r, c)'s force in the
  // first is node (c, r)'s in the second with x and y exchanged and negated. A bend family joined along one
  // axis only (the other's springs laid along the same one) resists one fold twice and the other not at all
  const int n = 7;
  const auto model = make_model("cloth", {{"rows", n}, {"columns", n}, {"width", 1.0}, {"height", 1.0}, {"structural", 0}, {"shear", 0},
                                          {"bend", 1}, {"g", 0}, {"wind_z", 0}, {"wind_coefficient", 0}, {"drag", 0}, {"damping", 0},
                                          {"pin_corners", 0}});
  ASSERT_EQ(model->size(), 6 * n * n);
  const auto folded = [&](bool along_rows) {
    Eigen::VectorXd y = model->initial_state();
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) y[3 * (r * n + c) + 2] = 0.05 * std::pow((along_rows ? r : c) - 3, 2);
    Eigen::VectorXd f(y.size());
    model->rhs(0, y, f);
    return Eigen::VectorXd(f.tail(3 * n * n));
  };
  const Eigen::VectorXd rows = folded(true), columns = folded(false);
  const double scale = std::max(rows.lpNorm<Eigen::Infinity>(), columns.lpNorm<Eigen::Infinity>());
  double worst = 0;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const Eigen::Vector3d a = rows.segment<3>(3 * (r * n + c)), b = columns.segment<3>(3 * (c * n + r));
      worst = std::max(worst, (a - Eigen::Vector3d(-b.y(), -b.x(), b.z())).lpNorm<Eigen::Infinity>());
    }
  std::cout << "bend springs, a fold along the rows and along the columns: largest restoring acceleration " << rows.lpNorm<Eigen::Infinity>()
            << " and " << columns.lpNorm<Eigen::Infinity>() << " m/s^2; the transposed fields differ by " << worst << '\n';
  EXPECT_GT(rows.lpNorm<Eigen::Infinity>(), 0) << "a fold along the rows stretches the bend springs down the columns";
  EXPECT_GT(columns.lpNorm<Eigen::Infinity>(), 0) << "a fold along the columns stretches those along the rows";
  EXPECT_LE(worst, tolerance::spring_force_roundoff * scale);
}

TEST(Cloth, TheDefiniteApproximationMakesTheStepMatrixPositiveDefiniteWhereTheExactOneIsNot) {
  // without damping and wind the exact K is symmetric, so its Cholesky factorisation is what fails
  const auto model = small_cloth({{"damping", 0}, {"wind_coefficient", 0}});
  const Eigen::VectorXd y = shaken(*model, 0.1, 5);  // several springs compressed
  const double h = 0.05;
  Stats stats;
  const CountedSystem counted(*model, stats);
  for (const bool definite : {true, false}) {
    BaraffWitkinSystem bw(counted, definite);
    bw.assemble_matrix(0, y, h);
    const Eigen::MatrixXd a(bw.matrix());
    const Eigen::VectorXd eigenvalues = symmetric_eigenvalues((a + a.transpose()) / 2);
    if (definite) {
      EXPECT_LT((a - a.transpose()).lpNorm<Eigen::Infinity>(), tolerance::accumulated_roundoff * a.lpNorm<Eigen::Infinity>());
      EXPECT_GT(eigenvalues.minCoeff(), 0);
    } else {
      EXPECT_LT(eigenvalues.minCoeff(), 0) << "this state should make the exact matrix indefinite";
    }
  }
  // so the exact Jacobian's Cholesky solve fails, named, with the step's time
  MassSpringImplicitOptions options;
  options.definite = false;
  auto stepper = make_mass_spring_implicit(counted, options);
  Eigen::VectorXd next;
  std::string failure;
  EXPECT_FALSE(stepper->step(0.25, h, y, next, failure));
  EXPECT_NE(failure.find("cholmod_factorize: matrix not positive definite"), std::string::npos) << failure;
  EXPECT_NE(failure.find("t = 0.25"), std::string::npos) << failure;
}

TEST(Cloth, ImplicitEulerIsItsOwnOrderAgainstCvodeOnASmallCloth) {
  // a 6 x 6 sheet hanging from two corners, 0.4 s, against CVODE BDF (KLU, the analytic sparse Jacobian)
  const auto model = make_model("cloth", {{"rows", 6}, {"columns", 6}, {"pin_corners", 0}, {"pin_top_corners", 1}, {"wind_coefficient", 0}});
  const double t_end = 0.4;
  const Measured reference = run_and_measure(*model, "cvode-bdf", StepControl::adaptive(1e-11, 1e-13), t_end, t_end);
  ASSERT_EQ(reference.result.status, Status::ok) << reference.result.message;
  for (const char* method : {"implicit-euler", "implicit-euler-newton", "fast-mass-spring"}) {
    std::vector<double> dts, errors;
    for (double dt = 4e-3; dt >= 2.4e-4; dt /= 2) {
      const Measured m = run_and_measure(*model, method, StepControl::fixed(dt), t_end, t_end);
      ASSERT_EQ(m.result.status, Status::ok) << method << " " << m.result.message;
      dts.push_back(dt);
      errors.push_back(max_norm_error(m.result.y_stop, reference.result.y_stop));
    }
    const double order = loglog_slope(dts, errors);
    EXPECT_NEAR(order, 1, tolerance::order_band) << method;
    std::cout << method << ": order " << order << ", error " << errors.back() << " at dt " << dts.back() << "\n";
  }
}

// Newton on the incremental potential from the inertial guess x0 + h v0 for one step of `model` at h from its
// initial state, exact (each direction from a fresh factor) or inexact: G at each iteration, and how fast each Newton
// step moves a node
struct NewtonTrace {
  std::vector<double> value, moved;
  std::string failure;
};
NewtonTrace newton_trace(const Model& model, double h, bool inexact) {
  Stats stats;
  const CountedSystem system(model, stats);
  IncrementalPotential potential(system, *system.as<MassSpringView>());
  const Eigen::VectorXd y0 = model.initial_state();
  potential.start(0, y0, h);
  NewtonTrace trace;
  PotentialNewton newton(NewtonOnPotential{.velocity_tolerance = 1e-8, .inexact = inexact, .observe = [&](int, double value, double moved) {
                                             trace.value.push_back(value);
                                             trace.moved.push_back(moved);
                                           }});
  Eigen::VectorXd x = potential.inertial();
  trace.failure = newton.minimise(potential, x, stats);
  return trace;
}

TEST(Cloth, NewtonOnTheIncrementalPotentialLowersItAtEveryIterationAndEndsQuadratically) {
  // the gusting flag's first step at 1/30 s (released flat at rest: its springs or elements compressed by the wind's
  // first push), springs and the continuum, by exact Newton (the Hessian's test): G falls at every iteration, and the
  // last steps shrink quadratically (each step's size the square of the last's, to a constant: the order of the sizes'
  // ratios near 2)
  for (const double continuum : {0.0, 1.0}) {
    const auto flag = make_model("cloth", {{"continuum", continuum}});
    const NewtonTrace trace = newton_trace(*flag, 1.0 / 30, false);
    ASSERT_TRUE(trace.failure.empty()) << trace.failure;
    for (size_t k = 1; k < trace.value.size(); ++k) EXPECT_LE(trace.value[k], trace.value[k - 1]) << "continuum " << continuum << ", iteration " << k;
    // the order of the last contraction above the tolerance (a step of 1e-8 m/s moves a node 3e-10 m at 1/30 s)
    std::optional<double> order;
    for (size_t k = 2; k < trace.moved.size(); ++k)
      if (trace.moved[k] > 1e-8 && trace.moved[k - 1] < 1e-2) order = std::log(trace.moved[k] / trace.moved[k - 1]) / std::log(trace.moved[k - 1] / trace.moved[k - 2]);
    ASSERT_TRUE(order.has_value()) << "continuum " << continuum << ": no steps between 1e-2 and 1e-8 m/s";
    std::cout << "continuum " << continuum << ": " << trace.moved.size() << " iterations, the last contraction of order " << *order << "\n";
    EXPECT_GT(*order, tolerance::newton_quadratic_order) << "continuum " << continuum;
  }
}

TEST(Cloth, InexactNewtonFindsExactNewtonsStepWithFewerFactorisations) {
  // the gusting flag's first half second at 1/60 s, springs and the continuum, each step's minimiser of G found from
  // the same state and the same first guess twice: by exact Newton and by the inexact one (CG preconditioned by the
  // step's first factor). At every step the inexact answer is one exact Newton, started there, finds converged (its
  // step below the tolerance), G lowered at every inexact iteration, and fewer factorisations. On the continuum the
  // two answers are within what the stopping rule leaves each (tolerances.hpp) at every step; the springs' sheet
  // buckles at its sixth step into one of two minima of G 0.45 mm apart (their G 1.6e-11 J apart), and the two
  // Newtons take one each: there only the first claim holds, as it must
  constexpr double h = 1.0 / 60;
  for (const double continuum : {0.0, 1.0}) {
    const auto flag = make_model("cloth", {{"continuum", continuum}});
    Stats exact_stats, inexact_stats, check_stats;
    const CountedSystem system(*flag, exact_stats);
    IncrementalPotential potential(system, *system.as<MassSpringView>());
    std::vector<double> values;
    double first_move = 0;
    PotentialNewton exact(NewtonOnPotential{.inexact = false});
    PotentialNewton inexact(NewtonOnPotential{.observe = [&](int, double value, double) { values.push_back(value); }});
    PotentialNewton check(NewtonOnPotential{.inexact = false, .observe = [&](int k, double, double moved) {
                                               if (k == 0) first_move = moved;
                                             }});
    const double tolerance = NewtonOnPotential{}.velocity_tolerance;
    Eigen::VectorXd y = flag->initial_state(), x_exact, x_inexact, x_check;
    const Eigen::Index n = y.size() / 2;
    double gap = 0;
    for (int step = 0; step < 30; ++step) {
      potential.start(step * h, y, h);
      x_exact = x_inexact = potential.inertial();
      ASSERT_EQ(exact.minimise(potential, x_exact, exact_stats), "");
      values.clear();
      ASSERT_EQ(inexact.minimise(potential, x_inexact, inexact_stats), "") << "continuum " << continuum << ", step " << step;
      for (size_t k = 1; k < values.size(); ++k) EXPECT_LE(values[k], values[k - 1]) << "continuum " << continuum << ", step " << step;
      x_check = x_inexact;
      ASSERT_EQ(check.minimise(potential, x_check, check_stats), "");
      EXPECT_LE(first_move, tolerance) << "continuum " << continuum << ", step " << step << ": the inexact answer is not converged";
      gap = std::max(gap, (x_inexact - x_exact).lpNorm<Eigen::Infinity>());
      if (continuum == 1) {
        EXPECT_LE((x_inexact - x_exact).lpNorm<Eigen::Infinity>(), tolerance::newton_stopping_gap * tolerance * h) << "step " << step;
      }
      y << x_exact, (x_exact - y.head(n)) / h;
    }
    std::cout << "continuum " << continuum << ": inexact Newton " << gap << " m from exact Newton's steps at most; factorisations "
              << inexact_stats.factorizations << " against " << exact_stats.factorizations << ", iterations " << inexact_stats.newton_iterations
              << " against " << exact_stats.newton_iterations << "\n";
    EXPECT_LT(inexact_stats.factorizations, exact_stats.factorizations) << "continuum " << continuum;
  }
}

TEST(Cloth, NewtonsAnswerIsConvergedWhereConjugateGradientsMeetNegativeCurvature) {
  // the continuum flag's first quarter second from rest at 1/60 s by implicit-euler-newton as a run steps it (the
  // linearised step, solved loosely on Newton's last factor, the first guess): the sheet buckles, G's exact Hessian at the first iterates is
  // indefinite, and CG on the step's factor stops at a direction of negative curvature (Newton-CG's truncation),
  // sometimes at its first. Every step's answer is converged as exact Newton, started there, judges it: converged at
  // its first iteration (its step below the velocity tolerance, or the decrease it predicts G's round-off)
  constexpr double h = 1.0 / 60;
  const auto flag = make_model("cloth", {{"continuum", 1.0}});
  Stats stats, check_stats;
  const CountedSystem system(*flag, stats);
  const auto stepper = make_mass_spring_implicit(system, MassSpringImplicitOptions{.newton = true});
  IncrementalPotential potential(system, *system.as<MassSpringView>());
  double first_move = 0;
  PotentialNewton check(NewtonOnPotential{.inexact = false, .observe = [&](int k, double, double moved) {
                                             if (k == 0) first_move = moved;
                                           }});
  Eigen::VectorXd y = flag->initial_state(), next, x;
  for (int step = 0; step < 15; ++step) {
    std::string failure;
    ASSERT_TRUE(stepper->step(step * h, h, y, next, failure)) << failure;
    potential.start(step * h, y, h);
    x = next.head(y.size() / 2);
    const long before = check_stats.newton_iterations;
    ASSERT_EQ(check.minimise(potential, x, check_stats), "") << "step " << step;
    EXPECT_EQ(check_stats.newton_iterations - before, 1) << "step " << step << ": exact Newton's first step from the answer moves a node at "
                                                         << first_move << " m/s";
    y.swap(next);
  }
}

TEST(Cloth, NewtonFromALooseFirstGuessEndsWhereFromAConvergedOne) {
  // implicit-euler-newton as a run steps it (factors kept) takes the linearised step only loosely, by CG on Newton's
  // last factor, as its first guess; refactorising, it solves that step exactly. From the same state each step (the
  // continuum flag's first half second from rest, through its buckling), the two answers are each converged to the
  // velocity tolerance, so within newton_stopping_gap of each other, and the loose guess costs no factorisation of
  // its own
  constexpr double h = 1.0 / 60;
  const auto flag = make_model("cloth", {{"continuum", 1.0}});
  Stats loose_stats, exact_stats;
  const CountedSystem loose_system(*flag, loose_stats), exact_system(*flag, exact_stats);
  const auto loose = make_mass_spring_implicit(loose_system, MassSpringImplicitOptions{.newton = true});
  const auto exact = make_mass_spring_implicit(exact_system, MassSpringImplicitOptions{.newton = true, .solve = LinearSolve::refactor});
  const double tolerance = NewtonOnPotential{}.velocity_tolerance;
  Eigen::VectorXd y = flag->initial_state(), from_loose, from_exact;
  const Eigen::Index n = y.size() / 2;
  double gap = 0;
  for (int step = 0; step < 30; ++step) {
    std::string failure;
    ASSERT_TRUE(loose->step(step * h, h, y, from_loose, failure)) << failure;
    ASSERT_TRUE(exact->step(step * h, h, y, from_exact, failure)) << failure;
    const double apart = (from_loose.head(n) - from_exact.head(n)).lpNorm<Eigen::Infinity>();
    EXPECT_LE(apart, tolerance::newton_stopping_gap * tolerance * h) << "step " << step;
    gap = std::max(gap, apart);
    y = from_exact;
  }
  std::cout << "answers at most " << gap << " m apart; factorisations " << loose_stats.factorizations << " against " << exact_stats.factorizations
            << ", Newton iterations " << loose_stats.newton_iterations << " against " << exact_stats.newton_iterations << "\n";
  EXPECT_LT(loose_stats.factorizations, exact_stats.factorizations);
}

TEST(Cloth, NewtonGivesUpAFactorThatWillNotServeAfterAFewConjugateGradients) {
  // the continuum flag's first half second from rest at 1/60 s, through its buckling, each step's minimiser of G found
  // from the same state twice: CG on the step's factor given up where its first iterations' rate predicts that it
  // would not converge within max_cg_iterations, and given up only after them. Both answers are converged to the
  // velocity tolerance, so within newton_stopping_gap of each other, and the probe spends fewer solves
  constexpr double h = 1.0 / 60;
  const auto flag = make_model("cloth", {{"continuum", 1.0}});
  Stats probed_stats, unprobed_stats;
  const CountedSystem system(*flag, probed_stats);
  IncrementalPotential potential(system, *system.as<MassSpringView>());
  PotentialNewton probed(NewtonOnPotential{}), unprobed(NewtonOnPotential{.cg_probe_iterations = 0});
  const double tolerance = NewtonOnPotential{}.velocity_tolerance;
  Eigen::VectorXd y = flag->initial_state(), x_probed, x_unprobed;
  const Eigen::Index n = y.size() / 2;
  double gap = 0;
  for (int step = 0; step < 30; ++step) {
    potential.start(step * h, y, h);
    x_probed = x_unprobed = potential.inertial();
    ASSERT_EQ(probed.minimise(potential, x_probed, probed_stats), "") << "step " << step;
    ASSERT_EQ(unprobed.minimise(potential, x_unprobed, unprobed_stats), "") << "step " << step;
    const double apart = (x_probed - x_unprobed).lpNorm<Eigen::Infinity>();
    EXPECT_LE(apart, tolerance::newton_stopping_gap * tolerance * h) << "step " << step;
    gap = std::max(gap, apart);
    y << x_unprobed, (x_unprobed - y.head(n)) / h;
  }
  std::cout << "answers at most " << gap << " m apart; solves " << probed_stats.linear_solves << " against " << unprobed_stats.linear_solves
            << ", factorisations " << probed_stats.factorizations << " against " << unprobed_stats.factorizations << ", Newton iterations "
            << probed_stats.newton_iterations << " against " << unprobed_stats.newton_iterations << "\n";
  EXPECT_LT(probed_stats.linear_solves, unprobed_stats.linear_solves);
}

TEST(Cloth, BackwardEulerRunsTheGustingFlagAtAnAnimatorsFrameSteps) {
  // 1/30, 1/60 and 1/120 s: every step converged, the springs over the first second (the report runs the scene's
  // whole 5 s), with its Newton iterations counted
  const auto flag = make_model("cloth", {});
  for (const double dt : {1.0 / 30, 1.0 / 60, 1.0 / 120}) {
    const Measured m = run_and_measure(*flag, "implicit-euler-newton", StepControl::fixed(dt), 1.0, 1.0);
    EXPECT_EQ(m.result.status, Status::ok) << dt << ": " << m.result.message;
    EXPECT_GE(m.result.stats.newton_iterations, m.result.stats.steps) << dt;
    std::cout << "dt " << dt << ": " << static_cast<double>(m.result.stats.newton_iterations) / static_cast<double>(m.result.stats.steps)
              << " Newton iterations a step, " << m.result.stats.line_search_halvings << " halvings\n";
  }
}

TEST(Cloth, TheContinuumsOwnDampingIsLinearInTheVelocityDissipatesAndSparesARigidSpin) {
  // f_damping(x, v) = J_v(x) v (the viscous stress is linear in the strain rate), v . f_damping <= 0, and a rigid spin
  // v = w x (x - c) (no strain rate) is not damped
  const Params free_sheet{{"continuum", 1}, {"pin_row", -1}, {"pin_column", -1}};
  Params with_damping = free_sheet;
  with_damping["rayleigh_beta"] = 1e-3;
  const auto damped = small_cloth(with_damping), undamped = small_cloth(free_sheet);
  const Eigen::Index n = damped->size() / 2;
  const MassSpringView& view = *damped->as<MassSpringView>();
  const auto damping_force = [&](const Eigen::VectorXd& y) {
    Eigen::VectorXd a(n), b(n);
    damped->as<SecondOrderView>()->acceleration(0, y, a);
    undamped->as<SecondOrderView>()->acceleration(0, y, b);
    Eigen::VectorXd f = a - b;
    for (int i = 0; i < view.nodes; ++i) f.segment<3>(3 * i) *= view.mass[i];
    return f;
  };
  for (const double spread : {0.02, 0.1}) {
    const Eigen::VectorXd y = shaken(*damped, spread, 5);
    const Eigen::VectorXd f = damping_force(y);
    // the damping's own df/dv: the damped sheet's less the undamped one's (drag and the wind's are in both)
    Eigen::SparseMatrix<double> k, d, d_undamped;
    view.force_jacobians(0, y, true, k, d);
    undamped->as<MassSpringView>()->force_jacobians(0, y, true, k, d_undamped);
    d -= d_undamped;
    const Eigen::VectorXd v = y.tail(n);
    EXPECT_LT((d * v - f).lpNorm<Eigen::Infinity>(), tolerance::damping_linear_map * (1 + f.lpNorm<Eigen::Infinity>())) << spread;
    EXPECT_LE(v.dot(f), 0) << spread;
    // a rigid spin about the sheet's centre
    Eigen::VectorXd spin = y;
    const Eigen::Vector3d w(0.3, -1.1, 0.7);
    for (int i = 0; i < view.nodes; ++i) spin.segment<3>(n + 3 * i) = w.cross(Eigen::Vector3d(y.segment<3>(3 * i)));
    EXPECT_LT(damping_force(spin).lpNorm<Eigen::Infinity>(), tolerance::damping_linear_map * (1 + f.lpNorm<Eigen::Infinity>())) << spread;
  }
}

TEST(Cloth, ImplicitEulerDampsASpringBy1OverSqrt1PlusOmegaSquaredHSquaredAStep) {
  for (const double wh : {0.1, 1.0, 3.0, 10.0})
    for (const double ratio : implicit_euler_amplitude_ratios(wh, 5))
      EXPECT_NEAR(ratio, 1 / std::sqrt(1 + wh * wh), tolerance::implicit_damping_roundoff) << "w h = " << wh;
}

TEST(Cloth, ExplicitMethodsFailWhereTheStiffestModePredictsAndImplicitEulerDoesNot) {
  for (const double c : {100.0, 1000.0}) {
    const auto model = stability_sheet(c);
    const StiffestMode mode = stiffest_mode(*model, 0, model->initial_state());
    const double symplectic = *mass_spring_stable_dt("symplectic-euler", mode), rk4 = *mass_spring_stable_dt("rk4", mode),
                 euler = *mass_spring_stable_dt("euler", mode);
    EXPECT_NEAR(measured_stable_dt(*model, "symplectic-euler", 2000, symplectic) / symplectic, 1, tolerance::stability_match) << c;
    const double rk4_ratio = measured_stable_dt(*model, "rk4", 2000, rk4) / rk4;
    EXPECT_GT(rk4_ratio, 1 - tolerance::stability_match) << c;
    EXPECT_LT(rk4_ratio, 1 + tolerance::rk4_probe_excess) << c;
    // explicit Euler lives only through the damping: its limit is the smallest, and the prediction is safe
    EXPECT_LT(euler, symplectic);
    EXPECT_GT(measured_stable_dt(*model, "euler", 2000, euler) / euler, 1 - tolerance::stability_match) << c;
    // implicit Euler at 100 times symplectic Euler's limit: bounded, its energy below where it started
    const Measured m = run_and_measure(*model, "implicit-euler", StepControl::fixed(100 * symplectic), 2.0, 2.0);
    ASSERT_EQ(m.result.status, Status::ok) << m.result.message;
    EXPECT_LT(*model->energy(m.result.y_stop), *model->energy(model->initial_state())) << c;
  }
}

// pins from a list: exactly the listed nodes leave the state and stay where they started while the rest fall
TEST(Cloth, PinsFromAListHoldExactlyTheListedNodes) {
  const Params params = resolve_params(*find_model("cloth"), {{"rows", 4}, {"columns", 5}, {"pin_corners", 0}, {"wind_coefficient", 0}});
  const std::vector<GridNode> pins{{0, 2}, {3, 4}, {0, 2}};  // one listed twice: pinned once
  const auto model = find_model("cloth")->make_with_pins(params, pins);
  EXPECT_EQ(model->size(), 6 * (4 * 5 - 2));
  const RunResult r = make_integrator("implicit-euler", StepControl::fixed(0.01))->integrate(*model, 0, model->initial_state(), std::vector<double>{0.5});
  ASSERT_EQ(r.status, Status::ok) << r.message;
  const TriangleMesh start = model->shapes(model->initial_state())->surfaces.front();
  const TriangleMesh end = model->shapes(r.y_stop)->surfaces.front();
  for (Eigen::Index k = 0; k < start.vertices.rows(); ++k) {
    const bool pinned = k == 0 * 5 + 2 || k == 3 * 5 + 4;
    if (pinned) EXPECT_EQ(end.vertices.row(k), start.vertices.row(k)) << "pinned node " << k;
    else EXPECT_LT(end.vertices(k, 1), start.vertices(k, 1)) << "free node " << k << " has not fallen";
  }
  for (const GridNode off : {GridNode{4, 0}, GridNode{0, 5}, GridNode{-1, 0}}) {
    const std::vector<GridNode> bad{off};
    try {
      find_model("cloth")->make_with_pins(params, bad);
      ADD_FAILURE() << "node [" << off[0] << ", " << off[1] << "] is off the grid";
    } catch (const BadParameter& e) {
      EXPECT_EQ(e.key, "pins");
    }
  }
}

TEST(Cloth, ASheetDroppedOnASphereStaysOutsideItAndAboveTheGround) {
  const double radius = 0.5, ground = -0.5;
  const auto model = make_model("cloth", {{"rows", 10}, {"columns", 10}, {"width", 2}, {"height", 2}, {"horizontal", 1}, {"elevation", 0.7},
                                          {"pin_corners", 0}, {"wind_coefficient", 0}, {"sphere_radius", radius}, {"ground", 1}, {"ground_y", ground}});
  const RunResult r = make_integrator("implicit-euler", StepControl::fixed(0.005))->integrate(*model, 0, model->initial_state(), output_times(1.5, 0.05));
  ASSERT_EQ(r.status, Status::ok) << r.message;
  EXPECT_GT(r.stats.projections, 0);
  double inside = 0, below = 0, touching = 0;
  for (const auto& y : r.trajectory.y)
    for (Eigen::Index i = 0; i < y.size() / 6; ++i) {
      const Eigen::Vector3d x = y.segment<3>(3 * i);
      inside = std::max(inside, radius - x.norm());
      below = std::max(below, ground - x.y());
      touching += std::abs(x.norm() - radius) < tolerance::obstacle_roundoff * radius;
    }
  EXPECT_LT(inside, tolerance::obstacle_roundoff * radius);
  EXPECT_LT(below, tolerance::obstacle_roundoff);
  EXPECT_GT(touching, 0) << "the sheet never reached the sphere";
}

}  // namespace
}  // namespace stepwise
