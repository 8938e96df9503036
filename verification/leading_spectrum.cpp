// leading_spectrum (stability.hpp): the eigenvalues of largest magnitude of a large system's Jacobian by restarted
// Arnoldi (Spectra), the whole spectrum of a small one.
#include "stability.hpp"

#include "solvers/fd_jacobian.hpp"

// GCC 12 sees a use after free in Spectra's UpperHessenbergEigen once inlined here (Eigen's aligned_free of a
// buffer it then no longer reads): a false positive in the library's code, silenced for this file alone
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuse-after-free"
#include <Spectra/GenEigsSolver.h>
#include <Spectra/MatOp/DenseGenMatProd.h>
#include <Spectra/MatOp/SparseGenMatProd.h>

#include <algorithm>
#include <type_traits>

namespace stepwise {

Eigen::VectorXcd leading_spectrum(const OdeSystem& system, double t, const Eigen::VectorXd& y) {
  const int n = system.size();
  if (n <= dense_spectrum_size) return jacobian_spectrum(system, t, y);
  const int nev = leading_eigenvalues, ncv = std::min(n, 4 * nev + 1);
  const auto largest = [&](auto& product) {
    Spectra::GenEigsSolver<std::decay_t<decltype(product)>> solver(product, nev, ncv);
    solver.init();
    solver.compute(Spectra::SortRule::LargestMagn, 1000, 1e-6);
    // the converged ones (none where Arnoldi did not converge: then the step and stiffness go unpredicted)
    return Eigen::VectorXcd(solver.eigenvalues());
  };
  if (const auto* sparse = system.as<SparseJacobian>()) {
    Eigen::SparseMatrix<double> j;
    sparse->sparse_jacobian(t, y, j);
    Spectra::SparseGenMatProd<double> product(j);
    return largest(product);
  }
  Eigen::MatrixXd j(n, n);
  jacobian_or_fd(system, t, y, j);
  Spectra::DenseGenMatProd<double> product(j);
  return largest(product);
}

}  // namespace stepwise

#pragma GCC diagnostic pop
