// Capability: f split into a stiff part, stepped implicitly, and the rest, stepped explicitly (the IMEX
// methods, arkode-imex-*). A model declares which forces are stiff: the cloth's springs and their damping,
// the water's Laplacian, the fluid's viscosity. The two parts add up to f to round-off (test_imex_split).
#pragma once

#include <stepwise/solvers/ode_system.hpp>

#include <functional>
#include <string_view>

namespace stepwise {

struct ImexSplit {
  using Part = std::function<void(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f)>;
  std::string_view stiff;  // what the implicit part is, in words ("the springs and their damping")
  Part implicit_part;      // f_I(t, y): the stiff forces (size() entries)
  Part explicit_part;      // f_E(t, y) = f - f_I: everything else
  // df_I/dy on a pattern that never changes (CSC), for a sparse direct solve of the Newton systems
  std::function<void(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::SparseMatrix<double>& dfdy)> implicit_jacobian;
  bool linear = false;  // f_I is linear in y and independent of t: one Newton iteration solves each stage
  // where f_I is linear with a direct solve cheaper than any matrix (the fluid's viscosity, diagonal in Fourier
  // space, dense on the grid): x <- (1 - gamma df_I/dy)^-1 x, in place of implicit_jacobian's sparse solve
  std::function<void(double gamma, Eigen::Ref<Eigen::VectorXd> x)> implicit_solve;
};

inline const Requirement needs_imex_split =
    needs<ImexSplit>("a model that declares a stiff/non-stiff split of f (a cloth, a water grid, a fluid)");

}  // namespace stepwise
