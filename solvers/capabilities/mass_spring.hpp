// Capability: a mass-spring network, y = (x, v) of `nodes` points in 3-D (x = y[0..3 nodes), node-major,
// then v), or in the plane (dimension 2: x = y[0..2 nodes)), each with a lumped mass, so that M dv/dt = f(t, x, v) with M diagonal: the structure Baraff &
// Witkin's linearised implicit Euler on a sparse Cholesky factor (implicit-euler, implicit-euler-newton),
// and the prefactored local/global method of Liu et al. 2013 (fast-mass-spring), need.
#pragma once

#include <stepwise/solvers/ode_system.hpp>

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <functional>
#include <vector>

namespace stepwise {

// a spring of the network (seeds: Hooke's law with Voigt damping) between nodes a and b, or from the fixed
// point `anchor` to node b (a = -1: a pin); models/springs.hpp has its forces and derivatives
struct Spring {
  int a = -1, b = 0;                                 // node indices; a = -1: the fixed point `anchor`
  double rest = 1;                                   // l (m)
  double stiffness = 0;                              // c (N/m)
  double damping = 0;                                // gamma (N s/m)
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();  // where a pinned spring hangs from (m)
};

// the elastic potential around one node, for a per-vertex solver (vbd): the energy of the terms (springs, elements,
// stencils) that touch it, their force on it, and that force's derivative by the node's own position (in the plane,
// their first two entries and leading 2 x 2 block; a solver ignores the rest)
struct VertexElastic {
  double energy = 0;                                   // J
  Eigen::Vector3d force = Eigen::Vector3d::Zero();     // N
  Eigen::Matrix3d jacobian = Eigen::Matrix3d::Zero();  // N/m
};

struct MassSpringView {
  int nodes = 0;
  int dimension = 3;            // each node's coordinates in x: 3, or 2 for a system in the plane x-y. The callbacks
                                // below take and give x, f and Jacobians of `dimension` entries a node
  std::vector<double> mass;     // kg per node
  std::vector<Spring> springs;  // the elastic springs f holds, which the prefactored method treats implicitly
                                // (every other force, their damping included, it holds at the step's start)
  // the force Jacobians K = df/dx and D = df/dv at (t, y) (f = M dv/dt, d nodes x d nodes (d = dimension), CSC, the same
  // pattern at every call); definite: K replaced by a symmetric negative semidefinite approximation and D
  // by its symmetric part (the model says which), so that M - h D - h^2 K is symmetric positive definite for
  // a Cholesky factor; exact otherwise. A method counts each call (run_support.hpp's force_jacobians)
  std::function<void(double t, const Eigen::Ref<const Eigen::VectorXd>& y, bool definite, Eigen::SparseMatrix<double>& dfdx,
                     Eigen::SparseMatrix<double>& dfdv)>
      force_jacobians;
  // the elastic potential Psi(x) (J) and its force f_e(x) = -grad Psi added into f (N, d nodes x 1): the part of
  // f that backward Euler as a minimisation holds implicitly (solvers/incremental_potential.hpp); the rest of f
  // (damping, drag, wind, gravity, a pick) it takes at the step's start. The definite K above is -grad^2 Psi
  // with each spring's or element's Hessian made semidefinite
  std::function<double(const Eigen::Ref<const Eigen::VectorXd>& x)> potential;
  std::function<void(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f)> elastic_force;
  // df_e/dx = -grad^2 Psi at x on force_jacobians' pattern: exact, or (definite) each spring's or element's
  // Hessian made semidefinite
  std::function<void(const Eigen::Ref<const Eigen::VectorXd>& x, bool definite, Eigen::SparseMatrix<double>& dfdx)> elastic_jacobian;
  // Psi's terms that touch node i at x: their energy, and with `derivatives` their force on node i and its 3 x 3 block
  // of df_e/dx (definite: each term's block made semidefinite). Two nodes that share no term (nor a block of
  // force_jacobians' pattern) can be evaluated and moved at once: a colour of vbd's
  std::function<void(int node, const Eigen::Ref<const Eigen::VectorXd>& x, bool definite, bool derivatives, VertexElastic& out)> vertex_elastic;
};

// each coordinate's lumped mass (dimension nodes x 1): the diagonal of M
inline Eigen::VectorXd coordinate_masses(const MassSpringView& view) {
  Eigen::VectorXd m(Eigen::Index{view.dimension} * view.nodes);
  for (int i = 0; i < view.nodes; ++i) m.segment(Eigen::Index{view.dimension} * i, view.dimension).setConstant(view.mass[static_cast<size_t>(i)]);
  return m;
}

// each node's springs (indices into springs, a node's in spring order), for a per-node view of them (vbd's sweep,
// the models' vertex_elastic)
inline std::vector<std::vector<int>> springs_by_node(const std::vector<Spring>& springs, int nodes) {
  std::vector<std::vector<int>> by(static_cast<size_t>(nodes));
  for (size_t k = 0; k < springs.size(); ++k) {
    by[static_cast<size_t>(springs[k].b)].push_back(static_cast<int>(k));
    if (springs[k].a >= 0) by[static_cast<size_t>(springs[k].a)].push_back(static_cast<int>(k));
  }
  return by;
}

inline const Requirement needs_mass_spring =
    needs<MassSpringView>("a mass-spring system: the scenes flag, flag-on-pole, hanging-cloth, cloth-on-sphere and hanging-chain, or "
                          "pendulum-cartesian with a compliant rod (--set compliance=1e-6)");

// Capability: a mass-spring system whose elastic forces are its MassSpringView's springs alone, as the
// prefactored local/global method needs (a spring cloth, a chain; not the continuum cloth, whose elastic
// forces are finite elements and whose view has no springs)
struct SpringNetworkView {
  const MassSpringView* network = nullptr;
};
inline const Requirement needs_spring_network =
    needs<SpringNetworkView>("a mass-spring system of springs alone: the scenes flag, flag-on-pole, hanging-cloth, cloth-on-sphere and "
                             "hanging-chain (not the continuum cloth, --set continuum=1), or pendulum-cartesian with a compliant rod "
                             "(--set compliance=1e-6)");

}  // namespace stepwise
