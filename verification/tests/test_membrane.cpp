// The continuum cloth's elements (models/membrane.hpp): the St. Venant-Kirchhoff membrane's force is minus its
// energy's gradient and its Jacobian the force's derivative (central differences), the definite Jacobian is
// negative semidefinite and the exact one where the element is stretched both ways, the quadratic bending
// force is its energy's gradient and vanishes on every flat placement, and a uniformly stretched sheet of them
// is in equilibrium at every interior node (the patch test).
#include "models/membrane.hpp"
#include "models/model.hpp"
#include "run/measure.hpp"
#include "solvers/capabilities/second_order.hpp"
#include "solvers/method_table.hpp"
#include "solvers/stability.hpp"
#include "verification/continuum_checks.hpp"
#include "verification/order_fit.hpp"
#include "verification/stability.hpp"
#include "verification/tolerances.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>
#include <random>

namespace stepwise {
namespace {

const MembraneMaterial material(5e5, 0.3, 5e-4);

// a right-ish triangle of the flag's size, 0.1 m, in the sheet's plane
MembraneElement element() { return make_membrane_element({0, 1, 2}, {0, 0}, {0.1, 0.01}, {0.02, 0.08}); }

// the rest corners in 3-D (z = 0), moved by up to `spread` of the element's
// size in each coordinate
Corners3 deformed(double spread, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Corners3 x{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.1, 0.01, 0), Eigen::Vector3d(0.02, 0.08, 0)};
  for (auto& c : x)
    for (int i = 0; i < 3; ++i) c[i] += spread * 0.1 * u(rng);
  return x;
}

Corners3 moved(Corners3 x, int coordinate, double by) {
  x[static_cast<size_t>(coordinate / 3)][coordinate % 3] += by;
  return x;
}

constexpr double fd_step = 6e-6 * 0.1;  // eps^(1/3) of the element's size

TEST(Membrane, ForceIsMinusTheEnergyGradient) {
  const MembraneElement e = element();
  for (const double spread : {0.05, 0.3}) {  // small strain, and large with compression
    const Corners3 x = deformed(spread, 7);
    const Vector9d f = membrane_force(material, e, x);
    Vector9d fd;
    for (int k = 0; k < 9; ++k)
      fd[k] = -(membrane_energy(material, e, moved(x, k, fd_step)) - membrane_energy(material, e, moved(x, k, -fd_step))) / (2 * fd_step);
    EXPECT_LT((f - fd).lpNorm<Eigen::Infinity>(), tolerance::element_fd * f.lpNorm<Eigen::Infinity>()) << "spread " << spread;
  }
}

TEST(Membrane, ForceJacobianIsTheForceDerivative) {
  const MembraneElement e = element();
  for (const double spread : {0.05, 0.3}) {
    const Corners3 x = deformed(spread, 11);
    const Matrix9d J = membrane_force_jacobian(material, e, x, false);
    Matrix9d fd;
    for (int k = 0; k < 9; ++k)
      fd.col(k) = (membrane_force(material, e, moved(x, k, fd_step)) - membrane_force(material, e, moved(x, k, -fd_step))) / (2 * fd_step);
    EXPECT_LT((J - fd).lpNorm<Eigen::Infinity>(), tolerance::element_fd * J.lpNorm<Eigen::Infinity>()) << "spread " << spread;
    // a force Jacobian of a potential is symmetric
    EXPECT_LT((J - J.transpose()).lpNorm<Eigen::Infinity>(), tolerance::element_roundoff * J.lpNorm<Eigen::Infinity>());
  }
}

TEST(Membrane, DefiniteJacobianIsSemidefiniteAndExactWhereStretchedBothWays) {
  const MembraneElement e = element();
  // stretched 1% and 2% along the sheet's two axes: StVK's Hessian is semidefinite there, and the definite one (the
  // geometric stiffness of the stress's tension alone) the same
  Corners3 stretched{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.101, 0.0102, 0), Eigen::Vector3d(0.0202, 0.0816, 0)};
  const Matrix9d exact = membrane_force_jacobian(material, e, stretched, false);
  EXPECT_LT((membrane_force_jacobian(material, e, stretched, true) - exact).lpNorm<Eigen::Infinity>(),
            tolerance::element_roundoff * exact.lpNorm<Eigen::Infinity>());
  // compressed: the exact Hessian has a negative eigenvalue, the definite one
  // none
  Corners3 compressed{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.09, 0.009, 0), Eigen::Vector3d(0.018, 0.072, 0)};
  const auto lowest = [](const Matrix9d& J) { return symmetric_eigenvalues(-(J + J.transpose()) / 2).minCoeff(); };
  const Matrix9d exact_compressed = membrane_force_jacobian(material, e, compressed, false);
  const double scale = exact_compressed.lpNorm<Eigen::Infinity>();
  EXPECT_LT(lowest(exact_compressed), -1e-3 * scale);
  EXPECT_GT(lowest(membrane_force_jacobian(material, e, compressed, true)), -tolerance::element_roundoff * scale);
  // what the definite Hessian adds to the exact one is the compressive principal stresses' geometric stiffness,
  // -s_k (w_i . q_k)(w_j . q_k) I: semidefinite, of rank three a compressive stress (compressed 10% both ways; 10%
  // across and stretched 10% down)
  Corners3 compressed_across{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.09, 0.011, 0), Eigen::Vector3d(0.018, 0.088, 0)};
  for (const auto& [x, compressive] : {std::pair{compressed, 2}, std::pair{compressed_across, 1}}) {
    const Matrix9d added = membrane_force_jacobian(material, e, x, false) - membrane_force_jacobian(material, e, x, true);
    const Eigen::VectorXd eigenvalues = symmetric_eigenvalues((added + added.transpose()) / 2);
    EXPECT_GT(eigenvalues.minCoeff(), -tolerance::element_roundoff * scale) << compressive;
    EXPECT_GT(eigenvalues.maxCoeff(), 1e-3 * scale) << compressive;
    EXPECT_EQ((eigenvalues.array() > tolerance::element_roundoff * scale).count(), 3 * compressive) << compressive;
  }
}

// an n x n grid of spacing 1 / (n - 1) in the x-y plane (node (r, c) is r n + c) and the plate's bending stencils on it
struct Grid {
  std::vector<Eigen::Vector3d> rest;
  std::vector<BendingStencil> stencils;
};
Grid grid(int n) {
  Grid g;
  const double h = 1.0 / (n - 1);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) g.rest.emplace_back(c * h, r * h, 0);
  g.stencils = plate_bending_stencils(n, n, h, h, material.poisson);
  return g;
}

std::vector<Eigen::Vector3d> placed(const BendingStencil& s, const std::vector<Eigen::Vector3d>& x) {
  std::vector<Eigen::Vector3d> out;
  for (const int k : s.node) out.push_back(x[k]);
  return out;
}

TEST(Membrane, BendingForceIsTheEnergyGradientAndVanishesWhenFlat) {
  const Grid g = grid(4);  // every kind of stencil: corner, edge and inside nodes, and cells
  const double D = material.bending;
  // any flat placement (rotated out of its plane, moved, stretched within it) has no bending force
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Eigen::Matrix3d in_plane = Eigen::Matrix3d::Identity();
  in_plane(0, 0) = 1.03, in_plane(0, 1) = 0.02, in_plane(1, 1) = 0.98;
  std::vector<Eigen::Vector3d> flat, folded = g.rest;
  for (const auto& x : g.rest) flat.push_back(R * in_plane * x + Eigen::Vector3d(0.3, -0.2, 0.1));
  for (size_t i = 0; i < folded.size(); ++i) folded[i].z() = 0.02 * std::sin(3.0 * static_cast<double>(i) + 1);
  for (const BendingStencil& s : g.stencils) {
    const double unit = D * s.Q.lpNorm<Eigen::Infinity>() * 0.5;  // a force of the stencil's size
    const std::vector<Eigen::Vector3d> on_flat = placed(s, flat);
    for (size_t i = 0; i < on_flat.size(); ++i) EXPECT_LT(bending_force_on(D, s, on_flat, i).norm(), tolerance::element_roundoff * unit);
    // folded: the force is minus the energy's gradient
    const std::vector<Eigen::Vector3d> x = placed(s, folded);
    for (size_t i = 0; i < x.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        auto plus = x, minus = x;
        plus[i][c] += fd_step, minus[i][c] -= fd_step;
        const double fd = -(bending_energy(D, s, plus) - bending_energy(D, s, minus)) / (2 * fd_step);
        EXPECT_NEAR(bending_force_on(D, s, x, i)[c], fd, tolerance::element_fd * unit) << "node " << i << " coordinate " << c;
      }
    EXPECT_GT(bending_energy(D, s, x), 0);
  }
}

TEST(Membrane, BendingEnergyOfACylinderIsThePlatesInEveryDirection) {
  // a 33 x 33 unit sheet wrapped isometrically onto a cylinder of radius 2 whose axis makes an angle with the
  // grid's: the plate's energy D / (2 R^2) per unit area (kappa_1 = 1 / R, kappa_2 = 0: nu (tr kappa)^2 + (1 - nu)
  // kappa:kappa = 1 / R^2 whatever nu), over the whole unit square
  const int n = 33;
  const Grid g = grid(n);
  const double R = 2, D = material.bending;
  for (const double angle : {0.0, 0.3, std::numbers::pi / 4, -std::numbers::pi / 4, std::numbers::pi / 2}) {
    const Eigen::Vector3d d(std::cos(angle), std::sin(angle), 0), axis(-std::sin(angle), std::cos(angle), 0);
    std::vector<Eigen::Vector3d> x;
    for (const auto& X : g.rest) {
      const double theta = X.dot(d) / R;
      x.push_back(R * std::sin(theta) * d + X.dot(axis) * axis + Eigen::Vector3d(0, 0, R * (1 - std::cos(theta))));
    }
    double energy = 0;
    for (const auto& s : g.stencils) energy += bending_energy(D, s, placed(s, x));
    const double plate = D / (2 * R * R);
    EXPECT_NEAR(energy / plate, 1, tolerance::cylinder_bending) << "angle " << angle;
  }
}

TEST(Membrane, BendingEnergyVanishesOnlyOnAffineMaps) {
  // kappa:kappa's part leaves no zero-energy mode but the affine maps (3 x 3 of them): the mean curvature alone would
  // leave every harmonic displacement, x^2 - y^2 and x y among them, which a free edge shows as flopping
  const int n = 6;
  const Grid g = grid(n);
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(n * n, n * n);
  for (const auto& s : g.stencils)
    for (size_t i = 0; i < s.node.size(); ++i)
      for (size_t j = 0; j < s.node.size(); ++j) Q(s.node[i], s.node[j]) += s.Q(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
  const Eigen::VectorXd eigenvalues = symmetric_eigenvalues(Q);
  const double largest = eigenvalues.maxCoeff();
  int zero = 0;
  for (const double l : eigenvalues) zero += l < tolerance::element_roundoff * largest;
  EXPECT_EQ(zero, 3);  // per coordinate: 1, X, Y
  // the saddle x y bends
  std::vector<Eigen::Vector3d> saddle;
  for (const auto& X : g.rest) saddle.emplace_back(X.x(), X.y(), 0.1 * X.x() * X.y());
  double energy = 0;
  for (const auto& s : g.stencils) energy += bending_energy(material.bending, s, placed(s, saddle));
  // kappa_XY = 0.1 everywhere: 2 (1 - nu) kappa_XY^2 D / 2 per unit area
  EXPECT_NEAR(energy / (material.bending * (1 - material.poisson) * 0.01), 1, tolerance::cylinder_bending);
}

TEST(Membrane, PatchTestAUniformlyStretchedSheetIsInEquilibriumInside) {
  // a free continuum sheet, no gravity, wind or drag, stretched 1% across and
  // 2% down (and sheared): every element has the same strain and stress, so the
  // interior nodes' forces cancel; the edges' carry the stress
  const auto model =
      make_model("cloth", {{"rows", 7}, {"columns", 6}, {"continuum", 1}, {"pin_corners", 0}, {"g", 0}, {"wind_coefficient", 0}, {"drag", 0}});
  Eigen::VectorXd y = model->initial_state();
  const Eigen::Index n = y.size() / 2;
  Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
  A(0, 0) = 1.01, A(1, 1) = 1.02, A(0, 1) = 0.005;
  for (Eigen::Index i = 0; i < n / 3; ++i) y.segment<3>(3 * i) = A * y.segment<3>(3 * i).eval();
  Eigen::VectorXd a(n);
  model->as<SecondOrderView>()->acceleration(0, y, a);
  const int rows = 7, columns = 6;
  double interior = 0, edge = 0;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      const double norm = a.segment<3>(3 * (r * columns + c)).norm();
      if (r == 0 || c == 0 || r == rows - 1 || c == columns - 1)
        edge = std::max(edge, norm);
      else
        interior = std::max(interior, norm);
    }
  EXPECT_GT(edge, 0);
  EXPECT_LT(interior, tolerance::element_roundoff * edge);
}

TEST(Membrane, AStretchedStripMeasuresTheMaterialsPoissonRatioAndModulus) {
  // a 4 x 1 m strip of 9 x 33 nodes stretched 0.1% along its length, free to narrow: linear elasticity's
  // answer, nu and E themselves, at every nu (plane stress)
  for (const double nu : {0.0, 0.3, 0.45}) {
    const UniaxialStretch s = uniaxial_stretch({{"continuum", 1}, {"nu", nu}, {"E", 5e5}}, 9, 1e-3);
    ASSERT_TRUE(s.failure.empty()) << s.failure;
    EXPECT_NEAR(s.nu, nu, tolerance::small_strain_elastic_constants * std::max(nu, 0.1)) << "nu " << nu;
    EXPECT_NEAR(s.E, 5e5, tolerance::small_strain_elastic_constants * 5e5) << "nu " << nu;
  }
}

TEST(Membrane, NewtonConvergesQuadraticallyOnAStretchedStrip) {
  // 5% stretch from the affine guess: several iterations. In tension the projected Hessian is the exact one, so
  // Newton's residuals fall quadratically: the observed order log(r3 / r2) / log(r2 / r1) of the last three
  // before round-off is about 2 (a linearly converging iteration's is 1)
  const UniaxialStretch s = uniaxial_stretch({{"continuum", 1}, {"nu", 0.3}}, 9, 0.05);
  ASSERT_TRUE(s.failure.empty()) << s.failure;
  std::vector<double> r;
  for (const double v : s.residuals)
    if (v > 1e-13) r.push_back(v);  // above round-off
  ASSERT_GE(r.size(), 3u);
  const size_t k = r.size() - 1;
  const double order = std::log(r[k] / r[k - 1]) / std::log(r[k - 1] / r[k - 2]);
  EXPECT_GT(order, tolerance::newton_order_floor) << r[k - 2] << " " << r[k - 1] << " " << r[k];
  std::cout << "residuals " << r[k - 2] << " " << r[k - 1] << " " << r[k] << ", order " << order << "\n";
}

// the continuum sheet the dynamics tests run: 8 x 8 nodes hanging from its two top corners, no wind
std::unique_ptr<Model> hanging_continuum(Params extra = {}) {
  Params p{{"rows", 8}, {"columns", 8}, {"continuum", 1}, {"pin_corners", 0}, {"pin_top_corners", 1}, {"wind_coefficient", 0}};
  for (const auto& [k, v] : extra) p[k] = v;
  return make_model("cloth", p);
}

TEST(Membrane, ExplicitLimitsAreTheStiffestModesAndTheContinuumsCflScale) {
  // the stiffest mode of M^-1 K (the definite K, at rest) predicts symplectic Euler's limit 2 / omega; the
  // membrane's wave speed c = sqrt(E / (rho (1 - nu^2))) puts it at the CFL scale dx / c: between a third of it
  // and it (the triangles' and the lumped edge nodes' stiffest mode is some times the square lattice's). Under a
  // hundredth of gravity, so that the sheet's stretch does not stiffen it (at full gravity the stretched corners
  // lower the measured limit by 1.8%)
  const auto model = hanging_continuum({{"g", 0.0981}});
  const StiffestMode mode = stiffest_mode(*model, 0, model->initial_state());
  const double predicted = *mass_spring_stable_dt("symplectic-euler", mode);
  EXPECT_NEAR(measured_stable_dt(*model, "symplectic-euler", 2000, predicted) / predicted, 1, tolerance::stability_match);
  const double c = std::sqrt(5e5 / (1000 * (1 - 0.3 * 0.3))), dx = 1.0 / 7;
  EXPECT_GT(predicted, dx / c / 3);
  EXPECT_LT(predicted, dx / c);
}

TEST(Membrane, SymplecticEulerKeepsTheUndampedSheetsEnergyInItsBand) {
  // no drag, no wind: the swinging sheet's energy under symplectic Euler oscillates in a band of width O(h) and
  // does not drift: its largest departure over the second 2.5 s is within twice the first's. At a quarter of the
  // limit at rest: swinging undamped, the corners' elements stretch and stiffen, and at half of it (2.11 ms) the
  // run turns unstable after 2 s (at 2.0 ms it does not)
  const auto model = hanging_continuum({{"drag", 0}});
  const StiffestMode mode = stiffest_mode(*model, 0, model->initial_state());
  const double dt = *mass_spring_stable_dt("symplectic-euler", mode) / 4;
  const RunResult r = make_integrator("symplectic-euler", StepControl::fixed(dt))->integrate(*model, 0, model->initial_state(), output_times(5.0, 0.01));
  ASSERT_EQ(r.status, Status::ok) << r.message;
  const double e0 = *model->energy(model->initial_state());
  double first = 0, second = 0;
  for (size_t k = 0; k < r.trajectory.t.size(); ++k)
    (r.trajectory.t[k] <= 2.5 ? first : second) = std::max(r.trajectory.t[k] <= 2.5 ? first : second, std::abs(*model->energy(r.trajectory.y[k]) - e0));
  EXPECT_GT(first, 0);
  EXPECT_LT(second, tolerance::symplectic_energy_band_growth * first);
}

// the order of `method` on `model` over 0.4 s against CVODE BDF (KLU, the exact sparse Jacobian) at rtol 1e-11, from
// 4 ms down by halving
double order_against_cvode(const Model& model, const char* method) {
  const double t_end = 0.4;
  const Measured reference = run_and_measure(model, "cvode-bdf", StepControl::adaptive(1e-11, 1e-13), t_end, t_end);
  EXPECT_EQ(reference.result.status, Status::ok) << reference.result.message;
  std::vector<double> dts, errors;
  for (double dt = 4e-3; dt >= 2.4e-4; dt /= 2) {
    const Measured m = run_and_measure(model, method, StepControl::fixed(dt), t_end, t_end);
    EXPECT_EQ(m.result.status, Status::ok) << method << ": " << m.result.message;
    dts.push_back(dt);
    errors.push_back(max_norm_error(m.result.y_stop, reference.result.y_stop));
  }
  const double order = loglog_slope(dts, errors);
  std::cout << method << ": order " << order << ", error " << errors.back() << " at dt " << dts.back() << "\n";
  return order;
}

TEST(Membrane, BackwardEulerIsFirstOrderOnTheDampedHangingContinuum) {
  // the continuum damped by its own viscous stress at the springs' rate (beta = gamma / c = 1e-4 s), hanging: Newton on
  // the incremental potential. (On the gusting flag at 8 x 8 the error falls at order 0.3-0.6 down to 1/4000 s: the
  // flat flag buckles in the wind, and its modes are not resolved)
  EXPECT_NEAR(order_against_cvode(*hanging_continuum({{"rayleigh_beta", 1e-4}}), "implicit-euler-newton"), 1, tolerance::order_band);
}

TEST(Membrane, ImplicitEulerIsFirstOrderOnTheHangingContinuum) {
  EXPECT_NEAR(order_against_cvode(*hanging_continuum(), "implicit-euler"), 1, tolerance::order_band);
}

}  // namespace
}  // namespace stepwise

namespace stepwise {
namespace {

TEST(Membrane, ASheetHeldAlongItsTopEdgeConvergesUnderRefinement) {
  // held along a line (not from two points, where plane elasticity is singular): the drop's successive differences
  // shrink at order >= 1 in the mesh size
  std::vector<double> drops;
  for (const int side : {8, 16, 32}) {
    const ClampedSheet s = clamped_sheet({{"continuum", 1}, {"nu", 0.3}}, side);
    ASSERT_TRUE(s.failure.empty()) << side << ": " << s.failure;
    drops.push_back(s.drop);
    std::cout << side << "^2: drop " << s.drop << " m, bottom width " << s.bottom_width << ", middle width " << s.middle_width << "\n";
  }
  // differences between meshes halving h: d1 = |D16 - D8|, d2 = |D32 - D16|, order log2(d1 / d2)
  const double order = std::log2(std::abs(drops[1] - drops[0]) / std::abs(drops[2] - drops[1]));
  std::cout << "order " << order << "\n";
  EXPECT_GT(order, tolerance::fem_refinement_order);
}

TEST(Membrane, AClampedPlateBendsAsKirchhoffsStripUnderRefinement) {
  // the aluminium plate clamped along an edge four spans long (bending_plate), its free edge's middle against
  // q L^4 / (8 D): the error shrinks at order >= 1 in the mesh size, and the Richardson extrapolation of the two finest
  // meshes is the strip's answer. The rigidity's 1 - nu^2 is 11% of it at nu = 0.33
  std::vector<double> ratio;
  for (const int side : {9, 17, 33}) {
    const BentStrip b = bent_strip(bending_plate(), side, bending_plate_aspect);
    ASSERT_TRUE(b.failure.empty()) << side << ": " << b.failure;
    ratio.push_back(b.tip_deflection / b.analytic);
    std::cout << side << " nodes along the span: tip " << b.tip_deflection << " m, strip " << b.analytic << " m, ratio " << ratio.back() << "\n";
  }
  const double order = std::log2(std::abs(ratio[1] - ratio[0]) / std::abs(ratio[2] - ratio[1]));
  const double extrapolated = 2 * ratio[2] - ratio[1];  // order 1: e(h) = c h
  std::cout << "order " << order << ", extrapolated ratio " << extrapolated << "\n";
  EXPECT_GT(order, tolerance::fem_refinement_order);
  EXPECT_NEAR(extrapolated, 1, tolerance::plate_strip_bending);
}

TEST(Membrane, AClampedPlateWithoutPoissonBendsAsABeamAtEveryWidth) {
  // at nu = 0 the plate does not curl across itself: the strip's answer is exact at any aspect, the square's too
  Params p = bending_plate();
  p["nu"] = 0;
  const BentStrip square17 = bent_strip(p, 17, 1), square33 = bent_strip(p, 33, 1), long33 = bent_strip(p, 33, bending_plate_aspect);
  ASSERT_TRUE(square17.failure.empty() && square33.failure.empty() && long33.failure.empty());
  EXPECT_NEAR(long33.tip_deflection / square33.tip_deflection, 1, tolerance::plate_strip_bending);
  EXPECT_NEAR((2 * square33.tip_deflection / square33.analytic - square17.tip_deflection / square17.analytic), 1, tolerance::plate_strip_bending);
}

}  // namespace
}  // namespace stepwise
