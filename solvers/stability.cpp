#include "stability.hpp"

#include "capabilities/mass_spring.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>

#include <stdexcept>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace stepwise {

double largest_stable_step(const std::function<std::complex<double>(std::complex<double>)>& R, const Eigen::VectorXcd& eigenvalues) {
  // the spectrum is as accurate as the Jacobian: a difference Jacobian's relative error is ~sqrt(machine
  // epsilon) = 1.5e-8, so an eigenvalue on the imaginary axis (an undamped mode) may come out with a positive real
  // part of that order of the largest |lambda|, and a zero (a fixed boundary value, an invariant) as a speck of
  // that size. Real parts up to this fraction of the largest are taken as 0, and eigenvalues smaller than it are
  // left out: R(0) = 1 for every consistent method, so zeros never grow.
  constexpr double jacobian_resolution = 1e-6;
  // what remains is exact to round-off: this much growth per step is taken as none
  constexpr double spectrum_growth_allowance = 1e-9;
  const double largest = eigenvalues.cwiseAbs().maxCoeff();
  std::vector<std::complex<double>> spectrum;
  // A mode with a larger positive real part is one the exact flow grows (Van der Pol's at mu = 1000: +0.56 beside
  // -3000): left out, as a method is asked to keep what decays from growing, not to damp what grows
  for (const auto& lambda : eigenvalues)
    if (std::abs(lambda) > jacobian_resolution * largest && lambda.real() < jacobian_resolution * largest)
      spectrum.emplace_back(lambda.real() > 0 ? 0.0 : lambda.real(), lambda.imag());
  if (spectrum.empty()) return std::numeric_limits<double>::infinity();
  const auto grows = [&](double h) {
    for (const auto& lambda : spectrum)
      if (std::abs(R(h * lambda)) > 1 + spectrum_growth_allowance) return true;
    return false;
  };
  double smallest = largest;
  for (const auto& lambda : spectrum) smallest = std::min(smallest, std::abs(lambda));
  double low = 1e-3 / largest;
  if (grows(low)) return 0.0;
  double high = 2 * low;
  while (!grows(high)) {
    low = high;
    high *= 2;
    if (low > 1e6 / smallest) return std::numeric_limits<double>::infinity();
  }
  while (high - low > 1e-9 * high) (grows((low + high) / 2) ? high : low) = (low + high) / 2;
  return low;
}

Eigen::Vector2cd oscillator_eigenvalues(double omega, double damping) {
  const std::complex<double> lambda(-damping, std::sqrt(std::max(omega * omega - damping * damping, 0.0)));
  return {lambda, std::conj(lambda)};
}

double symplectic_euler_oscillator_dt(double omega, double damping) {
  return 2 * (std::sqrt(damping * damping + omega * omega) - damping) / (omega * omega);
}

Eigen::VectorXcd dense_eigenvalues(const Eigen::MatrixXd& a) { return Eigen::EigenSolver<Eigen::MatrixXd>(a, false).eigenvalues(); }

Eigen::VectorXd symmetric_eigenvalues(const Eigen::MatrixXd& s, Eigen::MatrixXd* eigenvectors) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(s, eigenvectors ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
  if (eigenvectors) *eigenvectors = eigen.eigenvectors();
  return eigen.eigenvalues();
}

StiffestMode stiffest_mode(const OdeSystem& system, double t, const Eigen::VectorXd& y) {
  const MassSpringView* view = system.as<MassSpringView>();
  if (!view) throw std::invalid_argument("stiffest_mode: not a mass-spring system");
  Eigen::SparseMatrix<double> k, d;
  view->force_jacobians(t, y, false, k, d);
  const Eigen::Index n = k.rows();
  const Eigen::VectorXd root_mass = coordinate_masses(*view).cwiseSqrt();
  const Eigen::VectorXd inverse = root_mass.cwiseInverse();
  // S = M^-1/2 (-K) M^-1/2, symmetric for the springs' K (the wind's position part, not symmetric, is taken
  // symmetrised)
  Eigen::SparseMatrix<double> s = -(inverse.asDiagonal() * k * inverse.asDiagonal());
  s = (Eigen::SparseMatrix<double>(s.transpose()) + s) / 2;
  Eigen::VectorXd mode(n);
  double lambda = 0;
  if (n <= 3000) {
    Eigen::MatrixXd vectors;
    lambda = symmetric_eigenvalues(Eigen::MatrixXd(s), &vectors)[n - 1];
    mode = vectors.col(n - 1);
  } else {
    mode = Eigen::VectorXd::LinSpaced(n, 1, 2);
    for (int k = 0; k < 400; ++k) mode = (s * mode).normalized();
    lambda = mode.dot(s * mode);
  }
  const Eigen::VectorXd v = inverse.cwiseProduct(mode);  // the mode in coordinates: M^-1/2 times S's eigenvector
  const double a = 0.0 - v.dot(d * v) / (2 * v.dot(root_mass.cwiseAbs2().cwiseProduct(v)));  // 0.0 - : no "-0" where D is zero
  return {std::sqrt(std::max(lambda, 0.0)), a};
}

std::optional<double> fastest_decay(const OdeSystem& system, double t, const Eigen::VectorXd& y, int largest) {
  const int n = system.size();
  if (!system.as<DenseJacobian>() || n > largest) return std::nullopt;
  Eigen::MatrixXd j(n, n);
  system.as<DenseJacobian>()->jacobian(t, y, j);
  if (!j.allFinite()) return std::nullopt;
  const Eigen::VectorXcd lambda = dense_eigenvalues(j);
  double fastest = 0;
  for (const auto& l : lambda) fastest = std::max(fastest, -l.real());
  return fastest;
}

}  // namespace stepwise
