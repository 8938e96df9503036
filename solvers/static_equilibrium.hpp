// The static equilibrium of a mass-spring or continuum system (MassSpringView and SecondOrderView): the
// positions where the forces on the free coordinates vanish, f_free(x) = 0, some coordinates held where they
// are (a clamped edge, a prescribed stretch, a plane). Newton on CHOLMOD: each iteration solves
// -K_ff dx = f_free with K the model's definite force Jacobian (symmetric negative semidefinite: each element's
// Hessian projected, so that -K_ff has a Cholesky factor once the held coordinates remove the rigid motions),
// then a backtracking line search on |f_free| (Armijo on the residual: a step that does not reduce it is
// halved). On the definite K the iteration converges linearly where the exact Hessian is indefinite (compressed
// elements), quadratically where it is not. What the continuum cloth's study asks of a sheet at rest: its
// lateral contraction under a stretch, its sag under gravity.
#pragma once

#include <stepwise/solvers/ode_system.hpp>

#include <Eigen/Dense>

#include <string>
#include <vector>

namespace stepwise {

struct StaticEquilibrium {
  Eigen::VectorXd y;       // the state at equilibrium (velocities zero), or the last iterate
  int iterations = 0;      // Newton iterations
  double residual = 0;     // |f_free| at the end, relative to `scale`
  double scale = 0;        // the force it is relative to: the larger of |f| at the start and the held coordinates' reactions
  std::string failure;     // empty when converged; else why not
  std::vector<double> residuals;  // |f_free| / scale at the start and after each iteration
};

// from y (positions, then velocities, which are set to zero), holding the coordinates `held` marks (one per
// position coordinate), until |f_free| <= tolerance * scale; or, where no step lowers |f_free| any more (the
// round-off of a sum of large internal forces), within stall * scale
StaticEquilibrium static_equilibrium(const OdeSystem& system, Eigen::VectorXd y, const std::vector<bool>& held, double tolerance = 1e-10,
                                     double stall = 1e-8, int max_iterations = 200);

}  // namespace stepwise
