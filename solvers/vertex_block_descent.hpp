// Vertex Block Descent (Chen, Liu, Yang & Yuksel, "Vertex Block Descent", ACM TOG 43(4), SIGGRAPH 2024; NVIDIA Warp's
// VBDIntegrator): backward Euler's step as the minimiser of the incremental potential G
// (solvers/incremental_potential.hpp, the one backward Euler's Newton minimises), by Gauss-Seidel over the nodes.
// Each node in turn takes one Newton step on G as a function of its own position, the others held:
//     dx_i = -H_i^-1 g_i,   g_i = m_i / h^2 (x_i - xb_i) - (D0 (x - xb))_i / h - f0_i - f_e,i(x),
//     H_i = m_i / h^2 I - D0_ii / h - sum over the node's terms of their 3 x 3 block of df_e/dx_i, each made
//           semidefinite (its negative eigenvalues set to zero: the paper's remedy for an indefinite local Hessian),
// halved until G falls by Armijo's fraction of what the step predicts (kept where no halving does), so that no
// node's move raises G and a sweep never increases it. The nodes are coloured greedily (in their order) so that no
// two of a colour share a term of the elastic potential or a block of the force Jacobian; a colour's nodes move at
// once, on OpenMP's threads, each reading only nodes of other colours: the answer does not depend on the thread count.
#pragma once

#include <stepwise/solvers/fixed_step.hpp>
#include <stepwise/solvers/incremental_potential.hpp>

#include <Eigen/SparseCore>

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace stepwise {

// a node's move: accepted where G falls by this fraction of what the Newton step predicts, halved at most this many
// times (the shortest move tried is 2^-8 of the step; else the node stays). A device's sweep (gpu-vbd-compute) takes these
inline constexpr double vbd_armijo = 1e-4;
inline constexpr int vbd_max_halvings = 8;

// greedy colours of the nodes of a d x d block pattern (symmetric, d = dimension): each node the smallest colour none
// of its neighbours has, in node order; the nodes of each colour
std::vector<std::vector<int>> colour_nodes(const Eigen::SparseMatrix<double>& pattern, int dimension = 3);

// vbd's view of one step's potential G node by node, as its sweeps read it: the colours, and, for a network of springs
// alone (SpringNetworkView: a spring cloth, the chain, the compliant rod), each node's springs and its rows of D0 as 3 x 3
// blocks laid out contiguous in sweep order (colour by colour), as the paper's and Warp's kernels lay them out. Any other
// system's nodes (the continuum's elements) are read through IncrementalPotential::vertex. A node's move is the same
// on both: its Newton step on G, halved until G falls by Armijo's fraction of what it predicts; G's change along it
// written as a difference (the quadratic terms' exactly, a spring's as kernels/spring_end.hpp writes it), so that a
// halving costs the node's springs' lengths alone
class VbdNodes {
 public:
  // `springs`: the network whose springs are G's elastic terms, or nullptr (through IncrementalPotential::vertex).
  // The potential must be started; `refresh` after each start
  VbdNodes(const IncrementalPotential& potential, std::vector<std::vector<int>> colours, const MassSpringView* springs);
  // the step's D0, xb and f0 read again (D0's pattern is the view's, fixed)
  void refresh();
  const IncrementalPotential& potential() const { return potential_; }
  const std::vector<std::vector<int>>& colours() const { return colours_; }
  // the node at sweep slot k moved in x; G's decrease (0 where it stays)
  double move(size_t k, Eigen::VectorXd& x) const;

 private:
  struct NodeSpring {
    int other;                    // the other end's node, or -1: the fixed point `anchor`
    double rest, stiffness;
    std::array<double, 3> anchor;
  };
  template <int D>
  double move_in_network(size_t k, double* x) const;
  double move_through_vertex(int i, Eigen::VectorXd& x) const;

  const IncrementalPotential& potential_;
  std::vector<std::vector<int>> colours_;
  const MassSpringView* springs_;
  std::vector<int> order_;                    // the nodes in sweep order
  // slot k's springs are springs_at_[spring_end_[k - 1] .. spring_end_[k]), its blocks likewise (the first its own, (i, i))
  std::vector<int> spring_end_, block_end_;
  std::vector<NodeSpring> springs_at_;
  std::vector<int> block_node_;               // each block's column node j
  std::vector<double> blocks_;                // D0's blocks (i, j), row-major, d x d each
  std::vector<Eigen::Index> value_at_;        // where each of D0's stored values goes in blocks_
};

// one sweep over the colours, x moved in place on `threads` threads; G's decrease over it (J). `decrease` is scratch
// (each node's part, summed in node order: the same bits for any thread count)
double vbd_sweep(const VbdNodes& nodes, Eigen::VectorXd& x, int threads, Eigen::VectorXd& decrease);

// `sweeps` sweeps from x, in place; G's decrease over them (J). With rho > 0, Chebyshev's semi-iterative acceleration
// (Wang 2015, "A Chebyshev semi-iterative approach for accelerating projective and position-based dynamics", as the
// VBD paper takes it): after sweep k >= 2 the swept x^_k is carried on to
//     x_k = x_{k-2} + omega_k (x^_k - x_{k-2}),   omega_2 = 2 / (2 - rho^2),   omega_k = 4 / (4 - rho^2 omega_{k-1}),
// rho the sweeps' rate (the iteration's spectral radius), given: the paper sets it by hand for each scene. An
// extrapolation that would raise G is not taken, and the sequence starts again at omega_2: G still never rises
struct VbdSweeps {
  int sweeps = 1;
  int threads = 1;
  double rho = 0;  // Chebyshev's rate; 0: no acceleration
};
double vbd_iterate(const VbdNodes& nodes, Eigen::VectorXd& x, const VbdSweeps& how, Eigen::VectorXd& decrease);

// where a step's sweeps start: the inertial position x + h v (the step's guess with no force), or the paper's adaptive
// start (Chen et al. 2024, sec. 3.5; the authors' Gaia code): that plus h^2 times the part of the last step's
// acceleration along the other forces' acceleration a (gravity, wind), clamped to [0, |a|] (all of a at the first step)
enum class VbdStart { adaptive, inertial };

// the vbd methods' own settings (their options: solvers/methods/vbd.cpp declares them)
struct VbdSettings {
  int substeps = 1;    // backward Euler steps a step
  VbdSweeps sweeps;    // a (sub)step's sweeps, their threads and Chebyshev's rate
  VbdStart start = VbdStart::inertial;
};

struct Method;
struct MethodOption;
// the vbd methods' options (substeps, iterations, start; threads for the CPU's sweeps, rho for Chebyshev's), declared
// once for vbd, vbd-chebyshev and gpu-vbd-compute (solvers/methods/vbd.cpp), and their values in a run's control
std::vector<MethodOption> vbd_options(bool threads, bool chebyshev);
VbdSettings vbd_settings(const Method& method, const StepControl& control);

// The vbd method's step (and gpu-vbd-compute's) on a mass-spring system: each (sub)step is backward Euler's incremental
// potential minimised by `sweeps.sweeps` coloured sweeps from `start`. The nodes are coloured at the first step;
// summary.json's colours and G's decrease are counted
class VbdStepper : public FixedStepper {
 public:
  // `name` for a failure's message
  VbdStepper(const CountedSystem& system, const VbdSettings& settings, std::string_view name);
  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) override;

 protected:
  // the sweeps of one (sub)step from x, in place: vbd_iterate here; G's decrease over them added to `decrease` (J).
  // false, with `failure` naming the call, where they cannot be swept
  virtual bool iterate(const VbdNodes& nodes, Eigen::VectorXd& x, double& decrease, std::string& failure);
  const VbdSweeps& sweeps() const { return sweeps_; }
  const MassSpringView& view() const { return view_; }

 private:
  // one backward Euler step of length h from y (x, v), in place
  bool substep(double t, double h, Eigen::VectorXd& y, std::string& failure);

  const CountedSystem& system_;
  const MassSpringView& view_;
  IncrementalPotential potential_;
  int substeps_;
  VbdSweeps sweeps_;
  VbdStart start_;
  std::string_view name_;
  Eigen::Index n_;
  std::optional<VbdNodes> nodes_;  // made at the first step, its colours from the force Jacobian's pattern
  Eigen::VectorXd x_, decrease_, previous_v_;
  double previous_h_ = 0;
};

}  // namespace stepwise
