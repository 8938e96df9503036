// A sparse Cholesky factor A = L L^T of a symmetric positive definite matrix whose pattern never changes:
// analysed once (fill-reducing ordering, elimination tree, supernodes), refactorised per step with the
// analysis kept, solved for several right-hand sides at once. CHOLMOD does the work; its types stay in
// sparse_cholesky.cpp (RAII over cholmod_common, cholmod_sparse, cholmod_factor, cholmod_dense).
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <cmath>
#include <limits>
#include <memory>
#include <string>

namespace stepwise {

enum class Ordering {
  amd,     // approximate minimum degree
  metis,   // METIS nested dissection
  cheaper  // AMD; from metis_worth_trying unknowns on, METIS too, the one whose factor takes fewer flops kept
};

// below this many unknowns AMD's factor is the cheaper on the cloth meshes (32^2 and 64^2 nodes: 48 against 51
// and 424 against 481 Mflop) and METIS's analysis costs 2.5-4x AMD's, so `cheaper` asks METIS only above it
// (128^2 nodes: 4 312 against 5 228 Mflop, docs/performance.md)
inline constexpr long metis_worth_trying = 32768;

// what the analysis chose and what the factor will cost
struct CholeskyAnalysis {
  std::string ordering;     // "amd" or "metis"
  double factor_nonzeros = 0;  // entries of L
  double flops = 0;         // floating-point operations of one numeric factorisation
};

class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  // symbolic analysis of a's pattern (a symmetric, both triangles stored, CSC; only the lower one is read);
  // returns "" or the failing CHOLMOD call and its status
  std::string analyze(const Eigen::SparseMatrix<double>& a, Ordering ordering);
  // numeric factorisation of a (the analysed pattern, new values); "" or why not: a matrix that is not
  // positive definite names the column where the factorisation stopped
  std::string factorize(const Eigen::SparseMatrix<double>& a);
  // x = A^-1 b for each column of b with the last factor; "" or the failing CHOLMOD call and its status
  std::string solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const;
  const CholeskyAnalysis& analysis() const;
  // whether a factor is there to solve with (the last factorisation succeeded)
  bool factored() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// a factor of an earlier matrix as the preconditioner of Eigen's iterative solvers (their preconditioner
// interface; the factor is kept by its owner, so analysing and computing do nothing here)
// the iterations CG needs to bring a residual (or correction) from `start` to `goal`, predicted from `done` iterations
// that brought it to `now` at their geometric rate (preconditioned by a nearby matrix's factor, CG converges about
// geometrically); infinity where it did not fall
inline double predicted_iterations(double start, double now, int done, double goal) {
  const double rate = std::pow(now / start, 1.0 / done);
  return rate < 1 ? done + std::log(goal / now) / std::log(rate) : std::numeric_limits<double>::infinity();
}

class FactorPreconditioner {
 public:
  FactorPreconditioner() = default;
  template <class Matrix>
  FactorPreconditioner& analyzePattern(const Matrix&) { return *this; }
  template <class Matrix>
  FactorPreconditioner& factorize(const Matrix&) { return *this; }
  template <class Matrix>
  FactorPreconditioner& compute(const Matrix&) { return *this; }
  Eigen::ComputationInfo info() const { return Eigen::Success; }
  // a failed solve (CHOLMOD out of memory) gives NaN, which poisons the iteration: it fails to converge
  template <class Rhs>
  Eigen::VectorXd solve(const Rhs& r) const {
    rhs_ = r;
    if (!factor_->solve(rhs_, out_).empty()) out_.setConstant(rhs_.rows(), 1, std::numeric_limits<double>::quiet_NaN());
    return out_.col(0);
  }
  void use(const SparseCholesky* factor) { factor_ = factor; }

 private:
  const SparseCholesky* factor_ = nullptr;
  mutable Eigen::MatrixXd rhs_, out_;
};

}  // namespace stepwise
