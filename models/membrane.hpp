// The continuum cloth's element formulas (the second seed's "Continuum-Mechanics + FEM"): a thin sheet of
// linear triangles whose membrane is St. Venant-Kirchhoff on the Green strain, and whose bending is the
// isometric quadratic energy of Bergou, Wardetzky, Harmon, Zorin & Grinspun (2006), each with its exact force
// and force Jacobian. The model (models/cloth.cpp, `continuum = 1`) assembles them; nothing here steps.
//
// Membrane (Volino, Magnenat-Thalmann & Faure 2009; Kim & Eberle 2022 for the derivatives). A triangle with
// rest corners X0, X1, X2 in the sheet's own plane (2-D material coordinates) has Dm = [X1 - X0, X2 - X0]
// (2 x 2), rest area A = |det Dm| / 2. Deformed corners x_i (3-D): Ds = [x1 - x0, x2 - x0] (3 x 2), the
// deformation gradient F = Ds Dm^-1 (3 x 2), the Green strain E = (F^T F - I) / 2 (2 x 2). Plane stress,
// Young's modulus Y, Poisson's ratio nu, thickness h:
//     mu = Y / (2 (1 + nu)),   lambda = Y nu / (1 - nu^2),
//     psi = mu E:E + lambda tr(E)^2 / 2          (energy per unit rest volume),
//     W = A h psi,   S = 2 mu E + lambda tr(E) I,   P = F S   (first Piola-Kirchhoff, 3 x 2),
//     forces on x1, x2: the columns of -A h P Dm^-T; on x0 minus their sum.
// Its force Jacobian df/dx (9 x 9) is -d^2W/dx^2, exact: dP = dF S + F dS, dS = 2 mu dE + lambda tr(dE) I,
// dE = (dF^T F + F^T dF) / 2, for each of the nine coordinates. StVK's Hessian is indefinite under
// compression (a cloth's everyday state), which makes Newton's matrix M - h^2 K indefinite. The second variation is
// dF : dF S + dE : C : dE, the material's part semidefinite (C's moduli 2 mu and mu + lambda positive) and the
// geometric part sum_k s_k |dF q_k|^2 over S's principal stresses s_k and directions q_k, negative only along a
// compressive one: `definite` keeps S's tension alone in the geometric part (its negative principal stresses set to
// zero), the element's Hessian then semidefinite, so that the assembled matrix has a Cholesky factor. It is the
// continuum's form of the springs' definite Jacobian (a compressed spring's transverse stiffness dropped, Choi & Ko
// 2002: models/springs.hpp), exact on an element in tension both ways, and costs no eigendecomposition of the 9 x 9
// Hessian (whose projection, Teran, Sifakis, Irving & Fedkiw 2005, was 3.8 times the exact Hessian's assembly).
//
// Bending: Kirchhoff's plate, W_b = (D / 2) \int [nu (tr kappa)^2 + (1 - nu) kappa:kappa] dA with D = Y h^3 / (12 (1 - nu^2)),
// written, as Bergou, Wardetzky, Harmon, Zorin & Grinspun (2006) write its mean-curvature part, as a quadratic in the
// positions. For a flat rest sheet in Cartesian material coordinates (X across, Y down) and a deformation that does not
// stretch it, the second derivatives of the placement are the second fundamental form along the normal,
// x_{,IJ} = kappa_IJ n (the flat metric has no Christoffel symbols), so
//     nu |x_XX + x_YY|^2 + (1 - nu) (|x_XX|^2 + |x_YY|^2 + 2 |x_XY|^2) = nu (tr kappa)^2 + (1 - nu) kappa:kappa,
// quadratic in x, unchanged by any rotation, zero on any flat placement. Both parts are needed: the mean curvature alone
// (the cotangent Laplacian's energy) has a zero-energy mode for every harmonic displacement, which a sheet with free
// edges shows as edges that flop; kappa:kappa vanishes only on affine maps. On the grid: x_XX and x_YY by second
// differences at every node (central; one-sided on the edges, from the nearest three nodes), x_XY by the cell's four
// corners at its centre, each with the trapezoid rule's area (a node's dx dy, halved on an edge; a cell's dx dy). Each
// term is D / 2 x^T Q x on a few nodes, so the force -D Q x and the Jacobian -D Q (x the 3-D identity) are exact and
// constant: no dihedral angle, no indefinite bending term for Newton. On a cylinder of radius R the energy is D / (2 R^2)
// per unit area at any orientation on the grid; a cantilever's tip deflection converges to Kirchhoff's plate strip
// (test_membrane, verification/continuum_checks).
#pragma once

#include <Eigen/Dense>
#include <array>
#include <span>
#include <vector>

namespace stepwise {

// plane-stress Lame parameters and the plate's bending stiffness
struct MembraneMaterial {
  MembraneMaterial(double young, double poisson, double thickness);
  double young, poisson, thickness;
  double mu, lambda;  // Pa
  double bending;     // D, N m
};

struct MembraneElement {
  std::array<int, 3> node{};     // grid nodes
  Eigen::Matrix2d rest_inverse;  // Dm^-1
  double area = 0;               // rest area A (m^2)
};
MembraneElement make_membrane_element(std::array<int, 3> node, const Eigen::Vector2d& X0, const Eigen::Vector2d& X1, const Eigen::Vector2d& X2);

using Corners3 = std::array<Eigen::Vector3d, 3>;
using Vector9d = Eigen::Matrix<double, 9, 1>;
using Matrix9d = Eigen::Matrix<double, 9, 9>;

// F (3 x 2) and the Green strain
Eigen::Matrix<double, 3, 2> deformation_gradient(const MembraneElement& e, const Corners3& x);
Eigen::Matrix2d green_strain(const Eigen::Matrix<double, 3, 2>& F);
// the second Piola-Kirchhoff stress S (Pa) for a Green strain
Eigen::Matrix2d membrane_stress(const MembraneMaterial& m, const Eigen::Matrix2d& E);
// W, the corner forces (x0, x1, x2 stacked) and df/dx (definite: the semidefinite approximation above)
double membrane_energy(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x);
Vector9d membrane_force(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x);
Matrix9d membrane_force_jacobian(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, bool definite);

// for a per-vertex solver (vbd): the force on corner j alone and its derivative by that corner's position (the 3 x 3
// diagonal block of the force Jacobian, three of its columns; definite: that block of the semidefinite approximation)
void membrane_corner(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, int j, bool definite, Eigen::Vector3d& force,
                     Eigen::Matrix3d& jacobian);

// Damping of its own (the Kelvin-Voigt solid's viscous stress, a dissipation potential): the strain rate
// Edot = (F^T Fdot + Fdot^T F) / 2 drives the stress S_v = beta (2 mu Edot + lambda tr(Edot) I), the elastic law times a
// retardation time beta (s), forces as the elastic stress's with S_v for S. In the linear limit the force is -beta K v,
// Rayleigh's stiffness-proportional damping; at any deformation it is rotation-invariant (a rigid spin has Edot = 0)
// and it dissipates: v . f = -A h beta (2 mu Edot:Edot + lambda tr(Edot)^2) <= 0. A spring's Voigt damping gamma
// along its axis is the same law with beta = gamma / c, c its stiffness (f = -c (u.dx) u against -gamma (u.dv) u)
Vector9d membrane_damping_force(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, const Corners3& v, double beta);
// its derivative by the corners' velocities (symmetric negative semidefinite: minus beta times the elastic Hessian's
// stress-free part) and by their positions
Matrix9d membrane_damping_velocity_jacobian(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, double beta);
Matrix9d membrane_damping_position_jacobian(const MembraneMaterial& m, const MembraneElement& e, const Corners3& x, const Corners3& v, double beta);

struct BendingStencil {
  std::vector<int> node;  // grid nodes
  Eigen::MatrixXd Q;      // the energy is D / 2 sum_ij Q_ij x_i . x_j
};
// the plate's stencils on a rows x columns grid (node (r, c) is r columns + c) of rest spacing dx across and dy down: one a
// node (its x_XX and x_YY), one a cell (its x_XY)
std::vector<BendingStencil> plate_bending_stencils(int rows, int columns, double dx, double dy, double nu);
double bending_energy(double D, const BendingStencil& s, std::span<const Eigen::Vector3d> x);
// the force on the stencil's node i alone, -D (Q x)_i (its derivative by x_i is -D Q_ii times the identity)
Eigen::Vector3d bending_force_on(double D, const BendingStencil& s, std::span<const Eigen::Vector3d> x, size_t i);

}  // namespace stepwise
