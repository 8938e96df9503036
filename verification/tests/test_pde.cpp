// A user's own PDE (models/pde.hpp, docs/scenes.md#your-own-pde): the exact sparse Jacobian against central
// differences on every kind of side and operator, the compiled pointwise loop against the interpreter, the
// spatial order the stencils reach against exact solutions, at the boundary too (Dirichlet, Neumann and periodic
// sides, orders 2 and 4), and the seeds' wave equation as text against the built-in height field.
#include "models/pde.hpp"
#include "run/prepare.hpp"
#include "run/scene.hpp"
#include "solvers/fd_jacobian.hpp"
#include "solvers/method_table.hpp"
#include "verification/order_fit.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

namespace stepwise {
namespace {

std::unique_ptr<Model> pde_of(const std::string& toml, const Params& values = {}, bool compile = true) {
  const Scene scene = load_scene_text(toml, "test.toml");
  return make_pde(*scene.pde, values, compile);
}

// Gray-Scott on a periodic square, and viscous Burgers upwinded on [0, 1] with a Dirichlet and a Neumann side, both
// with formulas of t and position
const std::string gray_scott = R"toml(model = "pde"
fields = ["u", "v"]
[grid]
x = [0.0, 1.0]
y = [0.0, 1.0]
points = [6, 5]
[boundary.u]
x = "periodic"
y = "periodic"
[boundary.v]
x = "periodic"
y = "periodic"
[parameters]
Du = 2e-5
Dv = 1e-5
F = 0.04
k = 0.06
[initial]
u = "1 - 0.5*exp(-20*((x - 0.5)^2 + (y - 0.5)^2))"
v = "0.25*exp(-20*((x - 0.5)^2 + (y - 0.5)^2))"
[equations]
u = "Du*laplace(u) - u*v^2 + F*(1 - u)"
v = "Dv*laplace(v) + u*v^2 - (F + k)*v"
)toml";

const std::string burgers = R"toml(model = "pde"
fields = ["u"]
[grid]
x = [0.0, 1.0]
points = 9
[boundary.u]
left = { value = "1 + 0.1*sin(t)" }
right = { derivative = "0.5*t" }
[parameters]
nu = 0.05
[initial]
u = "1 + 0.5*sin(pi*x)"
[equations]
u = "nu*dxx(u) - upwind_dx(u - 1.2, u) + 0.1*x*dx(u)"
)toml";

TEST(Pde, TheSparseJacobianIsTheCentralDifferencesOfFOnItsPattern) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  const std::string heat = R"toml(model = "pde"
fields = ["u"]
[grid]
x = [0.0, 1.0]
points = 9
[boundary.u]
left = { value = "0" }
right = { derivative = "0" }
[parameters]
D = 0.1
[initial]
u = "sin(pi*x)"
[equations]
u = "D*laplace(u)"
)toml";
  // Burgers at order 4 too: its sides' ghosts are combinations of four and five values inside
  const Params order_4{{"order", 4}};
  for (const auto& [name, scene, values] : {std::tuple{"gray-scott", gray_scott, Params{}}, std::tuple{"burgers", burgers, Params{}},
                                            std::tuple{"heat", heat, Params{}}, std::tuple{"burgers order 4", burgers, order_4}}) {
    const auto compiled = pde_of(scene, values), interpreted = pde_of(scene, values, false);
    const int n = compiled->size();
    Eigen::VectorXd y = compiled->initial_state();
    for (int i = 0; i < n; ++i) y[i] += jitter(rng);  // no node on an upwind switch (u = 1.2)
    const double t = 0.3;
    Eigen::VectorXd f1(n), f2(n);
    compiled->rhs(t, y, f1);
    interpreted->rhs(t, y, f2);
    EXPECT_EQ(f1, f2) << name << ": the compiled loop and the interpreter run the same operations in the same order";
    Eigen::SparseMatrix<double> sparse, sparse2;
    compiled->as<SparseJacobian>()->sparse_jacobian(t, y, sparse);
    interpreted->as<SparseJacobian>()->sparse_jacobian(t, y, sparse2);
    EXPECT_EQ(Eigen::MatrixXd(sparse), Eigen::MatrixXd(sparse2)) << name;
    Eigen::MatrixXd fd(n, n);
    fd_jacobian(*compiled, t, y, fd);
    const Eigen::MatrixXd j = Eigen::MatrixXd(sparse);
    EXPECT_LE((j - fd).cwiseAbs().maxCoeff(), tolerance::jacobian_fd * (1 + j.cwiseAbs().maxCoeff())) << name << "\n" << j << "\n" << fd;
    // every diagonal entry is in the pattern (the Newton matrix I - h J has it), and nothing beyond the stencils: a
    // row of Burgers' holds its three neighbours (five at order 4, a side's ghosts reaching no farther), of
    // Gray-Scott's its field's five and the other field's centre
    for (int i = 0; i < n; ++i) {
      bool diagonal = false;
      for (Eigen::SparseMatrix<double>::InnerIterator it(sparse, i); it; ++it) diagonal = diagonal || it.row() == i;
      EXPECT_TRUE(diagonal) << name << ": diagonal " << i;
    }
    EXPECT_LE(sparse.nonZeros(), static_cast<Eigen::Index>(n) * (name == std::string("gray-scott") ? 6 : values.empty() ? 3 : 5)) << name;
  }
}

// the max error at t_end against [exact] on grids of n, 2n, 4n, 8n points, and its log-log slope against h
double spatial_order(const std::string& scene, const char* method, double t_end, int order, std::vector<int> points, double rtol = 1e-12) {
  std::vector<double> h, error;
  for (const int n : points) {
    const auto model = pde_of(scene, {{"points", n}, {"order", order}});
    const RunResult r = make_integrator(method, StepControl::adaptive(rtol, rtol / 100))->integrate(*model, 0, model->initial_state(), std::vector<double>{t_end});
    EXPECT_EQ(r.status, Status::ok) << r.message;
    h.push_back(1.0 / n);
    error.push_back((r.y_stop - pde_grid(*model)->exact(t_end)).cwiseAbs().maxCoeff());
    std::cout << "order " << order << ", " << n << " points: max error " << error.back() << "\n";
  }
  return loglog_slope(h, error);
}

TEST(Pde, TheHeatEquationConvergesAtTheStencilsOrderInSpaceWithDirichletAndNeumannSides) {
  // u = exp(-D pi^2 t) sin(pi x) under u = 0 at both ends; exp(-D pi^2 t) cos(pi x) under du/dn = 0
  const std::string heat = R"toml(model = "pde"
fields = ["u"]
[grid]
x = [0.0, 1.0]
points = 9
[parameters]
D = 0.1
[equations]
u = "D*laplace(u)"
)toml";
  const std::string dirichlet = heat + R"toml([boundary.u]
left = { value = "0" }
right = { value = "0" }
[initial]
u = "sin(pi*x)"
[exact]
u = "exp(-D*pi^2*t)*sin(pi*x)"
)toml";
  const std::string neumann = heat + R"toml([boundary.u]
left = { derivative = "0" }
right = { derivative = "0" }
[initial]
u = "cos(pi*x)"
[exact]
u = "exp(-D*pi^2*t)*cos(pi*x)"
)toml";
  // order 2, the mirrored ghost: from 17 points on. Order 4, the ghosts exact on quartics (an order below the
  // interior at the side): its errors fall 31-, 22- and 11-fold from 17 to 129 points before the boundary's and the
  // interior's error terms settle (14- and 16-fold to 513), so the order is read where they have, at 1e-9 to 5e-12,
  // with a time error far below (verner98 at rtol 1e-13: cvode-bdf at 1e-12 leaves 3e-11 at 257 points)
  for (const auto& scene : {dirichlet, neumann}) {
    EXPECT_NEAR(spatial_order(scene, "cvode-bdf", 1.0, 2, {17, 33, 65, 129}), 2.0, tolerance::order_band) << "order 2";
    EXPECT_NEAR(spatial_order(scene, "verner98", 1.0, 4, {129, 257, 513}, 1e-13), 4.0, tolerance::order_band) << "order 4";
  }
}

TEST(Pde, PeriodicAdvectionConvergesAtTheStencilsOrder) {
  const std::string advection = R"toml(model = "pde"
fields = ["u"]
[grid]
x = [0.0, 1.0]
points = 16
[boundary.u]
x = "periodic"
[parameters]
c = 1.0
[initial]
u = "sin(2*pi*x)"
[equations]
u = "-c*dx(u)"
[exact]
u = "sin(2*pi*(x - c*t))"
)toml";
  for (const int order : {2, 4}) EXPECT_NEAR(spatial_order(advection, "verner98", 1.0, order, {16, 32, 64, 128}), order, tolerance::order_band) << order;
}

// the seeds' wave equation as text (scenes/standing-wave-text.toml) against the built-in height field
// (standing-wave) on the same 64^2 grid, by rk4 at the same step: the same semi-discrete system, its Laplacian's
// terms summed in another order
TEST(Pde, TheWaveEquationAsTextIsTheBuiltInHeightFieldToRoundOff) {
  RunOptions text, built_in;
  text.scene_file = scenes_directory() + "/standing-wave-text.toml";
  built_in.scene_file = scenes_directory() + "/standing-wave.toml";
  for (RunOptions* o : {&text, &built_in}) {
    o->method = "rk4";
    o->dt = 5e-3;
  }
  const PreparedRun a = prepare_run(text), b = prepare_run(built_in);
  ASSERT_EQ(a.model->size(), b.model->size());
  ASSERT_EQ(a.t_end, b.t_end);
  const Eigen::VectorXd y0 = b.model->initial_state();
  Eigen::VectorXd f0(y0.size());
  b.model->rhs(0, y0, f0);
  const double largest_state = y0.cwiseAbs().maxCoeff(), largest_rate = f0.cwiseAbs().maxCoeff();
  EXPECT_LE((a.model->initial_state() - y0).cwiseAbs().maxCoeff(), tolerance::rewritten_formula_difference(0, 0, 0, 0, largest_state));
  const auto ra = make_integrator("rk4", a.control)->integrate(*a.model, 0, a.model->initial_state(), std::vector<double>{a.t_end});
  const auto rb = make_integrator("rk4", b.control)->integrate(*b.model, 0, y0, std::vector<double>{b.t_end});
  ASSERT_EQ(ra.status, Status::ok);
  ASSERT_EQ(rb.status, Status::ok);
  const long steps = std::lround(a.t_end / *a.control.dt);
  const double difference = (ra.y_stop - rb.y_stop).cwiseAbs().maxCoeff();
  std::cout << "text against built-in after " << steps << " steps: " << difference << " (the states' size " << rb.y_stop.cwiseAbs().maxCoeff() << ")\n";
  EXPECT_LE(difference, tolerance::rewritten_formula_difference(steps, *a.control.dt, a.t_end, largest_rate, largest_state));
  // and neither is the other trivially: the wave has moved
  EXPECT_GT((rb.y_stop - y0).cwiseAbs().maxCoeff(), 0.1 * largest_state);
}

}  // namespace
}  // namespace stepwise
