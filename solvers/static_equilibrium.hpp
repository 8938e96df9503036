// The static equilibrium of a mass-spring or continuum system (MassSpringView and SecondOrderView): the
// positions where the forces on the free coordinates vanish, f_free(x) = 0, some coordinates held where they
// are (a clamped edge, a prescribed stretch, a plane). Newton on CHOLMOD: each iteration solves -K_ff dx = f_free with
// K the model's exact force Jacobian where -K_ff has a Cholesky factor (quadratic convergence), else its definite one
// (each element's Hessian projected: linear convergence where the exact one is indefinite), then a backtracking line
// search that accepts a step lowering either the energy Pi = Psi - f_o . x (the elastic potential and the other
// forces' work, f_o taken where the iteration stands: exact for gravity) or |f_free| by Armijo's fraction. The energy
// is what a stiff membrane needs (a plate bent from flat: the residual of the midplane's stretch rejects the steps that
// lower Pi); the residual, where Pi's round-off hides its decrease. What the continuum cloth's study asks of a sheet at
// rest: its lateral contraction under a stretch, its sag under gravity, a clamped plate's bending.
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
// position coordinate), until |f_free| <= tolerance * scale, or Newton's step is within stall of the positions' size;
// or, where no step lowers |f_free| or Pi any more (the round-off of a sum of large internal forces), within
// stall * scale
StaticEquilibrium static_equilibrium(const OdeSystem& system, Eigen::VectorXd y, const std::vector<bool>& held, double tolerance = 1e-10,
                                     double stall = 1e-8, int max_iterations = 200);

}  // namespace stepwise
