#include "newton_matrix.hpp"

#include "fd_jacobian.hpp"
#include "run_support.hpp"

namespace stepwise {
namespace {

class DenseNewtonMatrix final : public NewtonMatrix {
 public:
  explicit DenseNewtonMatrix(const CountedSystem& s) : system_(s), jac_(s.size(), s.size()) {}

  bool factor(double t, const Eigen::VectorXd& y, double h) override {
    jacobian_or_fd(system_, t, y, jac_);
    ++system_.stats().jac_evals;
    ++system_.stats().factorizations;
    lu_.compute(Eigen::MatrixXd::Identity(jac_.rows(), jac_.cols()) - h * jac_);
    // singular when a pivot is zero or not finite: the determinant, their product, over- or underflows on a
    // large system (8192 unknowns of the water drop: reported singular when it was not)
    const auto pivots = lu_.matrixLU().diagonal();
    return pivots.allFinite() && (pivots.array() != 0).all();
  }

  void solve(const Eigen::VectorXd& r, Eigen::VectorXd& d) override {
    ++system_.stats().linear_solves;
    d = lu_.solve(r);
  }

 private:
  const CountedSystem& system_;
  Eigen::MatrixXd jac_;  // df/dy (n x n)
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;
};

}  // namespace

std::unique_ptr<NewtonMatrix> make_dense_newton_matrix(const CountedSystem& system) {
  return std::make_unique<DenseNewtonMatrix>(system);
}

}  // namespace stepwise
