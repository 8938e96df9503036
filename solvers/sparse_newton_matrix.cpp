// The Newton matrix I - h J of a large system with a sparse Jacobian, factorised by UMFPACK (SuiteSparse's
// multifrontal LU, through Eigen's UmfPackSupport): the symbolic analysis once on the fixed pattern, the numeric
// factorisation at each factor(). On a 2-D grid it is the fastest of the sparse LUs at hand as the grid grows
// (bench_pde, Gray-Scott's I - J at 2 x 128^2: UMFPACK 0.36 s, KLU's refactorisation 0.53 s, Eigen's SparseLU
// 1.4 s; at 2 x 64^2 the three are within 1.5x of each other, 51-74 ms).
#include "newton_matrix.hpp"

#include "blas_threads.hpp"
#include "run_support.hpp"

#include <Eigen/UmfPackSupport>

namespace stepwise {
namespace {

class SparseNewtonMatrix final : public NewtonMatrix {
 public:
  explicit SparseNewtonMatrix(const CountedSystem& s) : system_(s) { keep_blas_on_this_thread(); }
  bool factor(double t, const Eigen::VectorXd& y, double h) override {
    system_.as<SparseJacobian>()->sparse_jacobian(t, y, jac_);
    ++system_.stats().jac_evals;
    ++system_.stats().factorizations;
    if (identity_.rows() != jac_.rows()) {
      identity_.resize(jac_.rows(), jac_.cols());
      identity_.setIdentity();
    }
    w_ = identity_ - h * jac_;
    w_.makeCompressed();
    if (!analysed_) {
      lu_.analyzePattern(w_);
      analysed_ = true;
    }
    lu_.factorize(w_);
    return lu_.info() == Eigen::Success;
  }
  void solve(const Eigen::VectorXd& r, Eigen::VectorXd& out) override {
    ++system_.stats().linear_solves;
    out = lu_.solve(r);
  }

 private:
  const CountedSystem& system_;
  Eigen::SparseMatrix<double> jac_, identity_, w_;
  Eigen::UmfPackLU<Eigen::SparseMatrix<double>> lu_;
  bool analysed_ = false;
};

}  // namespace

std::unique_ptr<NewtonMatrix> make_sparse_newton_matrix(const CountedSystem& system) { return std::make_unique<SparseNewtonMatrix>(system); }

std::unique_ptr<NewtonMatrix> make_newton_matrix(const CountedSystem& system) {
  if (system.as<SparseJacobian>() && system.size() >= sparse_newton_from) return make_sparse_newton_matrix(system);
  return make_dense_newton_matrix(system);
}

}  // namespace stepwise
