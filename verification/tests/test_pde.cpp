// A user's own PDE (models/pde.hpp, docs/scenes.md#your-own-pde): the exact sparse Jacobian against central
// differences on every kind of side and operator, the compiled pointwise loop against the interpreter, and the
// spatial order the stencils reach against exact solutions, at the boundary too (Dirichlet and Neumann sides,
// order 2; periodic, orders 2 and 4).
#include "models/pde.hpp"
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
  for (const auto& [name, scene] : {std::pair{"gray-scott", gray_scott}, std::pair{"burgers", burgers}, std::pair{"heat", heat}}) {
    const auto compiled = pde_of(scene), interpreted = pde_of(scene, {}, false);
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
    // row of Burgers' holds its three neighbours, of Gray-Scott's its field's five and the other field's centre
    for (int i = 0; i < n; ++i) {
      bool diagonal = false;
      for (Eigen::SparseMatrix<double>::InnerIterator it(sparse, i); it; ++it) diagonal = diagonal || it.row() == i;
      EXPECT_TRUE(diagonal) << name << ": diagonal " << i;
    }
    EXPECT_LE(sparse.nonZeros(), static_cast<Eigen::Index>(n) * (name == std::string("gray-scott") ? 6 : 3)) << name;
  }
}

// the max error at t_end against [exact] on grids of n, 2n, 4n, 8n points, and its log-log slope against h
double spatial_order(const std::string& scene, const char* method, double t_end, int order, std::vector<int> points) {
  std::vector<double> h, error;
  for (const int n : points) {
    const auto model = pde_of(scene, {{"points", n}, {"order", order}});
    const RunResult r = make_integrator(method, StepControl::adaptive(1e-12, 1e-14))->integrate(*model, 0, model->initial_state(), std::vector<double>{t_end});
    EXPECT_EQ(r.status, Status::ok) << r.message;
    h.push_back(1.0 / n);
    error.push_back((r.y_stop - model->exact(t_end)).cwiseAbs().maxCoeff());
    std::cout << "order " << order << ", " << n << " points: max error " << error.back() << "\n";
  }
  return loglog_slope(h, error);
}

TEST(Pde, TheHeatEquationConvergesAtSecondOrderInSpaceWithDirichletAndNeumannSides) {
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
  for (const auto& scene : {dirichlet, neumann}) EXPECT_NEAR(spatial_order(scene, "cvode-bdf", 1.0, 2, {17, 33, 65, 129}), 2.0, tolerance::order_band);
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

}  // namespace
}  // namespace stepwise
