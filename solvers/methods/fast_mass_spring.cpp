// The prefactored local/global method of Liu, Bargteil, O'Brien & Kavan (SIGGRAPH Asia 2013, "Fast
// simulation of mass-spring systems"), for a mass-spring system (MassSpringView, solvers/capabilities/mass_spring.hpp).
//
// Implicit Euler for the elastic springs is the minimisation of
//   g(x) = 1/(2h^2) (x - y)^T M (x - y) + sum_s c_s/2 |x_b - x_a - d_s|^2 - x . f_ext,   y = x0 + h v0,
// over x and over directions d_s with |d_s| = l_s (the spring's energy is the minimum over d). Alternating:
//   local:  d_s = l_s (x_b - x_a) / |x_b - x_a|                      (each spring on its own)
//   global: (M + h^2 L) x = M y + h^2 (J d + f_ext)                  (one sparse system)
// where L is the springs' Laplacian (c_s on the ends' diagonals, -c_s between them; a pinned spring adds c_s
// to its node and c_s times its anchor to the right-hand side). M + h^2 L is constant: factored once
// (CHOLMOD) as one scalar n x n matrix, and the global step solves it for the three coordinates (two in the plane)
// as as many right-hand sides. Every force that is not an elastic spring (gravity, drag, wind, the springs' Voigt
// damping, a picked node's pull) is f_ext, held at the step's start: explicit, which bounds how much
// damping a step can take. A fixed number of iterations (the paper's 10) per step; then v1 = (x1 - x0) / h.
#include "solvers/fixed_step.hpp"
#include "solvers/run_support.hpp"
#include "solvers/mass_spring_implicit.hpp"
#include "solvers/sparse_cholesky.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace stepwise {
namespace {

using Nodes = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;  // a row per node, as y stores them
using Row = Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, 3>;             // one node's, on the stack

class FastMassSpring final : public FixedStepper {
 public:
  explicit FastMassSpring(const CountedSystem& s) : system_(s), view_(*s.as<MassSpringView>()), second_order_(*s.as<SecondOrderView>()), n_(view_.nodes), d_(view_.dimension) {
    std::vector<Eigen::Triplet<double>> entries;
    for (const Spring& s : view_.springs) {
      entries.emplace_back(s.b, s.b, s.stiffness);
      if (s.a < 0) continue;
      entries.emplace_back(s.a, s.a, s.stiffness);
      entries.emplace_back(s.a, s.b, -s.stiffness);
      entries.emplace_back(s.b, s.a, -s.stiffness);
    }
    for (int i = 0; i < n_; ++i) entries.emplace_back(i, i, 0.0);
    laplacian_.resize(n_, n_);
    laplacian_.setFromTriplets(entries.begin(), entries.end());
    mass_ = Eigen::Map<const Eigen::VectorXd>(view_.mass.data(), n_);
    a_ = Eigen::VectorXd(Eigen::Index{d_} * n_);
  }

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string& failure) override {
    if (h != factored_h_ && !factor(h, t, failure)) return false;
    const Eigen::Index m = Eigen::Index{d_} * n_;
    const Eigen::Map<const Nodes> x0(y.data(), n_, d_), v0(y.data() + m, n_, d_);
    // every force but the elastic springs', at the step's start: M a - f_elastic(x0)
    second_order_acceleration(system_, second_order_, t, y, a_, f_);
    const Eigen::Map<const Nodes> a0(a_.data(), n_, d_);
    elastic(x0, directions(x0), f_el_);
    external_ = mass_.asDiagonal() * a0 - f_el_;
    inertia_ = mass_.asDiagonal() * (x0 + h * v0);

    x_ = x0 + h * v0;
    for (int iteration = 0; iteration < fast_mass_spring_iterations; ++iteration) {
      rhs_ = inertia_ + h * h * (spring_pull(directions(x_)) + external_);
      if (auto e = cholesky_.solve(rhs_, solution_); !e.empty()) {
        failure = fmt::format("fast-mass-spring: {} at t = {:.9g}", e, t);
        return false;
      }
      x_ = solution_;
      system_.stats().linear_solves += d_;
    }
    y_next.resize(y.size());
    Eigen::Map<Nodes>(y_next.data(), n_, d_) = x_;
    Eigen::Map<Nodes>(y_next.data() + m, n_, d_) = (x_ - x0) / h;
    return true;
  }

 private:
  bool factor(double h, double t, std::string& failure) {
    Eigen::SparseMatrix<double> q = h * h * laplacian_;
    q.diagonal() += mass_;
    q.makeCompressed();
    std::string e = analysed_ ? std::string() : cholesky_.analyze(q, Ordering::cheaper);
    analysed_ = e.empty();
    if (e.empty()) e = cholesky_.factorize(q);
    if (!e.empty()) {
      failure = fmt::format("fast-mass-spring: {} at t = {:.9g}", e, t);
      return false;
    }
    ++system_.stats().factorizations;
    factored_h_ = h;
    return true;
  }

  // the local step: each spring's direction scaled to its rest length (one row per spring)
  const Nodes& directions(const Nodes& x) {
    directions_.resize(static_cast<Eigen::Index>(view_.springs.size()), d_);
    for (size_t k = 0; k < view_.springs.size(); ++k) {
      const Spring& s = view_.springs[k];
      const Row r = x.row(s.b) - (s.a < 0 ? Row(s.anchor.head(d_).transpose()) : Row(x.row(s.a)));
      directions_.row(static_cast<Eigen::Index>(k)) = s.rest * r / r.norm();
    }
    return directions_;
  }

  // J d plus the anchors' pull: the part of the springs' forces that does not depend on x through L
  const Nodes& spring_pull(const Nodes& d) {
    pull_.setZero(n_, d_);
    for (size_t k = 0; k < view_.springs.size(); ++k) {
      const Spring& s = view_.springs[k];
      const Row cd = s.stiffness * d.row(static_cast<Eigen::Index>(k));
      pull_.row(s.b) += cd;
      if (s.a < 0)
        pull_.row(s.b) += s.stiffness * s.anchor.head(d_).transpose();
      else
        pull_.row(s.a) -= cd;
    }
    return pull_;
  }

  // the springs' elastic forces at x with directions d: -L x + J d + anchors (exact when d is the local step's)
  void elastic(const Nodes& x, const Nodes& d, Nodes& f) { f = spring_pull(d) - laplacian_ * x; }

  const CountedSystem& system_;
  const MassSpringView& view_;
  const SecondOrderView& second_order_;
  int n_, d_;  // nodes, and each node's coordinates
  Eigen::SparseMatrix<double> laplacian_;
  Eigen::VectorXd mass_, a_, f_;  // f_: f where the model has no acceleration of its own
  SparseCholesky cholesky_;
  bool analysed_ = false;
  double factored_h_ = 0;
  Nodes directions_, pull_, f_el_, external_, inertia_, x_, rhs_;
  Eigen::MatrixXd solution_;
};

}  // namespace

std::unique_ptr<FixedStepper> make_fast_mass_spring(const CountedSystem& system) {
  if (!system.as<MassSpringView>() || !system.as<SecondOrderView>()) throw std::invalid_argument("fast-mass-spring needs a mass-spring system");
  return std::make_unique<FastMassSpring>(system);
}

void register_fast_mass_spring_methods(MethodTable& table) {
  table.add({
      .name = "fast-mass-spring",
      .family = Family::fast_mass_spring,
      .source = Source::hand_written,
      .description = "mass-spring systems: prefactored local/global implicit Euler of the springs (Liu et al. 2013), "
                     "other forces explicit, fixed step",
      .order = {1, 1, "1"},
      .stepping = Stepping::fixed,
      .needs = needs_spring_network,
      .make = fixed_steps(make_fast_mass_spring),
  });
}

}  // namespace stepwise
