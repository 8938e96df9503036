// Mass, centre of mass and inertia tensor of a solid of uniform density bounded by a closed triangle
// mesh (polyhedral mass properties: Mirtich, "Fast and accurate computation of polyhedral mass
// properties", J. Graphics Tools 1(2), 1996, in the form of Eberly, "Polyhedral Mass Properties
// (Revisited)", Geometric Tools, 2002). By the divergence theorem the volume integrals of 1, x, y, z,
// x^2, y^2, z^2, xy, yz, zx become sums over the faces of polynomials in the vertex coordinates, exact
// for a polyhedron:
//   m = rho V,  c = (1/V) int r dV,  I = rho int (|r - c|^2 1 - (r - c)(r - c)^T) dV  (about c, mesh axes).
// The principal frame diagonalises I: I = R diag(I1, I2, I3) R^T with I1 <= I2 <= I3 and R a rotation.
#pragma once

#include <stepwise/models/triangle_mesh.hpp>

#include <Eigen/Dense>

namespace stepwise {

struct MassProperties {
  double volume = 0;                                   // m^3
  double mass = 0;                                     // kg
  Eigen::Vector3d center = Eigen::Vector3d::Zero();    // centre of mass (m), mesh frame
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();   // about the centre of mass, mesh axes (kg m^2)
};

// throws std::invalid_argument for a mesh that is not closed and consistently oriented, is inside out
// (negative volume), or encloses no volume, and for a density that is not positive and finite
MassProperties mass_properties(const TriangleMesh& mesh, double density);

// the inertia tensor about a point displaced by `offset` from the centre of mass (parallel-axis theorem,
// Steiner): I + m (|a|^2 1 - a a^T)
Eigen::Matrix3d shifted_inertia(const Eigen::Matrix3d& inertia, double mass, const Eigen::Vector3d& offset);

// the index of a principal moment larger than the sum of the other two (no body has such moments: I3 =
// rho int x^2 + y^2 <= I1 + I2), or -1 when there is none
int moment_beyond_the_others(const Eigen::Vector3d& moments);

struct PrincipalFrame {
  Eigen::Vector3d moments;   // I1 <= I2 <= I3 (kg m^2)
  Eigen::Matrix3d axes;      // columns: the principal axes in the mesh frame, a proper rotation (det +1)
};

// throws std::invalid_argument for a tensor that is not symmetric positive definite (to round-off), or
// whose moments break the triangle inequality I1 + I2 >= I3 that every real body obeys
PrincipalFrame principal_frame(const Eigen::Matrix3d& inertia);

}  // namespace stepwise
