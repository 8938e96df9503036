// Stable steps from what a method's stability is known by (method.hpp's Stability): the largest step for a
// spectrum from R(z), and the closed forms on a damped oscillator mode that more than one method shares.
#pragma once

#include <optional>

#include <stepwise/solvers/ode_system.hpp>

#include <Eigen/Dense>

#include <complex>
#include <functional>
#include <tuple>

namespace stepwise {

// The largest h with |R(h lambda)| <= 1 for every eigenvalue (not empty): h is raised by factors of 2 from
// 1e-3 / max |lambda| until some |R| exceeds 1 + 1e-9, then bisected to 1e-9. Positive real parts below 1e-6 of
// the largest |lambda| are taken as 0 and smaller eigenvalues left out (a difference Jacobian resolves no
// finer); larger positive real parts are modes the exact flow grows, left out too. 0 where even the first h grows
// (explicit Euler on an undamped spectrum), infinity where no h up to 1e6 / min |lambda| grows (implicit Euler).
double largest_stable_step(const std::function<std::complex<double>(std::complex<double>)>& R, const Eigen::VectorXcd& eigenvalues);

// the eigenvalues of the damped oscillator x'' = -omega^2 x - 2 a x': lambda = -a +- i sqrt(omega^2 - a^2)
Eigen::Vector2cd oscillator_eigenvalues(double omega, double damping);

// symplectic Euler on that oscillator: amplification [[1 - h^2 w^2, h (1 - 2 h a)], [-h w^2, 1 - 2 h a]],
// determinant 1 - 2 h a, trace 2 - h^2 w^2 - 2 h a; |trace| <= 1 + determinant gives h^2 w^2 <= 4 - 4 h a, so
// h < 2 (sqrt(a^2 + w^2) - a) / w^2 (h w < 2 undamped; the damping, explicit, shrinks it). The CPU and the GPU
// symplectic Euler share it.
double symplectic_euler_oscillator_dt(double omega, double damping);

// The stiffest mode of a mass-spring system (MassSpringView, solvers/capabilities/mass_spring.hpp) linearised at (t, y): omega^2, the
// largest eigenvalue of M^-1 (-K) with the exact K = df/dx (of the symmetric M^-1/2 (-K) M^-1/2: Eigen's
// self-adjoint eigensolver up to 3000 unknowns, else 400 power iterations, whose Rayleigh quotient then sits
// within the top cluster of eigenvalues), and its damping rate a = v^T (-D) v / (2 v^T M v).
struct StiffestMode {
  double omega = 0;    // rad/s
  double damping = 0;  // 1/s
  static auto fields(auto& s) { return std::tie(s.omega, s.damping); }
};
StiffestMode stiffest_mode(const OdeSystem& system, double t, const Eigen::VectorXd& y);

// The dense eigenvalue problems, instantiated here once (Eigen's EigenSolver<MatrixXd> costs some 17 s of a file's
// compile, its SelfAdjointEigenSolver<MatrixXd> some 7): a square matrix's eigenvalues (no vectors), and a symmetric
// one's (its lower triangle read), ascending, with their eigenvectors as columns when asked
Eigen::VectorXcd dense_eigenvalues(const Eigen::MatrixXd& a);
Eigen::VectorXd symmetric_eigenvalues(const Eigen::MatrixXd& s, Eigen::MatrixXd* eigenvectors = nullptr);

// a stiffness this large (t_end times the fastest decay rate) holds an explicit method to steps far below what
// accuracy asks: rk4 is stable for h |lambda| < 2.8, so it needs at least stiffness / 2.8 steps whatever the error
inline constexpr double stiffness_threshold = 1000;

// the fastest decay rate max(-Re lambda, 0) of the system's exact Jacobian at (t, y) (dense eigenvalues), or
// nothing where the system has no Jacobian or more than `largest` unknowns
std::optional<double> fastest_decay(const OdeSystem& system, double t, const Eigen::VectorXd& y, int largest = 1000);

}  // namespace stepwise
