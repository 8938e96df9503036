// The multipliers of particles held by distance constraints (solvers/capabilities/distance_constraints.hpp):
// positions moved along the constraints' gradients until every constraint is met to rounding (Newton's method,
// each iteration one LU of G(x) W G(x_dir)^T), and velocities projected onto the constraints' tangent space (one
// linear solve). RATTLE's two halves (solvers/methods/rattle.cpp) and the projection any ODE method's state can
// be given after each step (--constraint project: run/constrained_model.hpp) are these.
#pragma once

#include <stepwise/solvers/capabilities/distance_constraints.hpp>

#include <Eigen/SparseCore>
#include <Eigen/SparseLU>

#include <string>
#include <utility>
#include <vector>

namespace stepwise {

// one unit direction a row (3 entries, `dimension` used and the rest 0), each row contiguous for
// DistanceConstraints::violation
using Directions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

class ConstraintSolver {
 public:
  explicit ConstraintSolver(const DistanceConstraints& c);

  // each constraint's unit direction at x (a row each)
  void directions(const double* x, Directions& n) const;
  // x moved by W G(along)^T dlambda until g(x) = 0 to the rounding of its coordinates, `v` (if not null) by the
  // same over `h` (RATTLE's velocity moves with its positions); false with the reason in `why` if Newton's
  // iteration does not converge or the system is singular. Leaves the directions at the final x in at_end()
  bool meet(double* x, const Directions& along, double* v, double h, std::string& why);
  // v onto G(x) v = 0, G at the x of the last meet() (at_end())
  void tangent(double* v);
  const Directions& at_end() const { return n1_; }

 private:
  Eigen::VectorXd solve(const Directions& u, const Directions& w, const Eigen::VectorXd& r);
  void move(double* z, const Directions& n, const Eigen::VectorXd& s) const;
  double magnitude(const DistanceConstraint& c, const double* z) const;

  const DistanceConstraints& c_;
  Eigen::Index m_;
  Directions n1_;
  std::vector<std::vector<std::pair<int, double>>> touching_;  // a particle's constraints, with the sign of its end
  Eigen::SparseMatrix<double> A_;  // the multipliers' system, above dense_below constraints
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu_;
  bool analysed_ = false;
};

}  // namespace stepwise
