// Springs of a mass-spring system (seeds: Hooke's law with Voigt damping): between nodes a and b, with
// r = x_b - x_a, L = |r|, u = r / L, elongation e = L - l and its rate de/dt = u . (v_b - v_a), the force
//   F = (c e + gamma de/dt) u  on a,  -F on b.
// Its exact derivatives (w = v_b - v_a):
//   dF/dr = c u u^T + (c e + gamma de/dt) / L (1 - u u^T) + gamma / L u w^T (1 - u u^T),   dF/dw = gamma u u^T,
// with dF/dx_a = -dF/dr, dF/dx_b = dF/dr (and the same for v). These are what CVODE's Newton iteration wants.
//
// A Cholesky solve needs M - h D - h^2 K symmetric positive definite, and the exact dF/dr is neither
// symmetric (the damping's last term) nor, for a compressed spring (e < 0, so the middle term's
// coefficient is negative), semidefinite. The definite approximation drops the damping's derivatives by
// position (Baraff & Witkin 1998, section 5.2: they are not symmetric, and leaving them out only weakens
// the damping's implicitness) and clamps the transverse stiffness to c max(0, 1 - l / L) (Choi & Ko 2002,
// "Stable but responsive cloth", section 4: a compressed spring's transverse term is what makes the
// matrix indefinite, and dropping it is what keeps the implicit step stable through buckling):
//   dF/dr ~ c u u^T + c max(0, 1 - l / L) (1 - u u^T),   symmetric positive semidefinite.
#pragma once

#include <stepwise/solvers/capabilities/mass_spring.hpp>

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <array>
#include <span>
#include <utility>
#include <vector>

namespace stepwise {

// Each function below reads and writes `dimension` coordinates a node (3; 2 for a network in the plane x-y, whose springs
// then have no z), and hands out 3-vectors and 3 x 3 blocks whose entries past `dimension` a caller ignores.

// f[d i .. d i + d) += the springs' forces on node i; x, v, f hold d = dimension entries per node
void add_spring_forces(std::span<const Spring> springs, const double* x, const double* v, double* f, int dimension = 3);

// the springs' potential energy, sum c e^2 / 2
double spring_energy(std::span<const Spring> springs, const double* x, int dimension = 3);
// the springs `which` (indices into springs), each touching `node`, added to a per-vertex solver's view of it: their
// energy and, with `derivatives`, their elastic force on the node and its derivative by the node's position (definite:
// the semidefinite approximation of add_spring_force_jacobians)
void add_springs_at_node(std::span<const Spring> springs, std::span<const int> which, int node, const double* x, bool definite, bool derivatives,
                         VertexElastic& out, int dimension = 3);

// the fixed sparsity of a network's dn x dn force Jacobians (d = dimension): a d x d block on the diagonal of every node
// and at (i, j) and (j, i) for every pair of nodes a force couples (a spring's ends, a triangle's corners).
// Blocks are added straight into the matrix's values, so a Jacobian is refilled every step without
// triplets or a change of pattern (what a Cholesky factor analysed once relies on)
class BlockPattern {
 public:
  BlockPattern(int nodes, std::span<const std::pair<int, int>> pairs, int dimension = 3);
  // m becomes the dn x dn matrix with this pattern, every value zero (its storage reused when it has the
  // pattern already)
  void zero(Eigen::SparseMatrix<double>& m) const;
  // where block (i, j) lies in the values: i == j, or i and j a pair given (throws std::out_of_range
  // otherwise); found once, used every step
  struct Slot {
    Eigen::Index first = 0;   // value index of the block's (0, 0) entry
    Eigen::Index stride = 0;  // from one of its columns to the next
    int dimension = 3;        // the block's rows and columns
  };
  Slot slot(int i, int j) const;
  // m(d i .. d i + d, d j .. d j + d) += b's leading d x d block at a slot
  static void add(Eigen::SparseMatrix<double>& m, Slot slot, const Eigen::Matrix3d& b) {
    double* v = m.valuePtr() + slot.first;
    for (int c = 0; c < slot.dimension; ++c, v += slot.stride)
      for (int r = 0; r < slot.dimension; ++r) v[r] += b(r, c);
  }
  void add(Eigen::SparseMatrix<double>& m, int i, int j, const Eigen::Matrix3d& b) const { add(m, slot(i, j), b); }

 private:
  int nodes_, dimension_;
  std::vector<int> column_start_;  // block column j's block rows are rows_[column_start_[j] .. column_start_[j + 1])
  std::vector<int> rows_;          // sorted within a column
};

// the node pairs the springs couple (pinned springs couple none)
std::vector<std::pair<int, int>> spring_pairs(std::span<const Spring> springs);

// each spring's blocks in a pattern: (b, b), then for a spring between nodes (a, a), (a, b), (b, a)
std::vector<std::array<BlockPattern::Slot, 4>> spring_slots(std::span<const Spring> springs, const BlockPattern& pattern);

// K += dF/dx and D += dF/dv summed over the springs (node forces by node positions and velocities), exact
// or definite (above); K and D have the pattern the slots were found in. Without D (null) K alone, the springs at
// rest relative to each other (v unread): the elastic Jacobian
void add_spring_force_jacobians(std::span<const Spring> springs, std::span<const std::array<BlockPattern::Slot, 4>> slots, const double* x,
                                const double* v, bool definite, Eigen::SparseMatrix<double>& dfdx, Eigen::SparseMatrix<double>* dfdv,
                                int dimension = 3);

// the Jacobian of y' = (v, M^-1 f) for y = (x, v) from the force Jacobians K = df/dx, D = df/dv and the
// lumped node masses (each node's coordinates, dfdx.rows() / mass.size() of them, sharing its mass): [[0, I], [M^-1 K, M^-1 D]]
void mass_spring_jacobian(const Eigen::SparseMatrix<double>& dfdx, const Eigen::SparseMatrix<double>& dfdv, std::span<const double> mass,
                          Eigen::SparseMatrix<double>& dfdy);

// A network whose elastic forces are its springs alone, as a MassSpringView (and its SpringNetworkView): the springs'
// potential, elastic force and Jacobian and per-node terms, and the force Jacobians of the springs (their damping
// included) and of a linear drag (-m drag v on each node). A model whose other forces do not depend on the state
// (gravity) offers view() and network() as they are: the hanging chain (in 3-D) and the compliant pendulum-cartesian
// (one pinned spring in the plane)
class SpringNetwork {
 public:
  SpringNetwork(std::vector<double> mass, std::vector<Spring> springs, int dimension = 3, double drag = 0);
  SpringNetwork(const SpringNetwork&) = delete;  // its view's functions hold `this`
  SpringNetwork& operator=(const SpringNetwork&) = delete;
  const MassSpringView& view() const { return view_; }
  const SpringNetworkView& network() const { return network_; }
  // K = df/dx and D = df/dv at (x, v), exact or definite (above), on the network's pattern
  void force_jacobians(const double* x, const double* v, bool definite, Eigen::SparseMatrix<double>& dfdx, Eigen::SparseMatrix<double>& dfdv) const;

 private:
  MassSpringView view_;
  SpringNetworkView network_{&view_};
  double drag_;
  BlockPattern pattern_;
  std::vector<std::array<BlockPattern::Slot, 4>> slots_;
  std::vector<std::vector<int>> by_node_;
};

}  // namespace stepwise
