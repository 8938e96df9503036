// A constrained scene's model with its state put back onto its constraints after every step of any ODE method
// (--constraint project): the positions moved along the constraints' gradients, weighted by the inverse masses,
// until every constraint is met to rounding, then the velocities onto the constraints' tangent
// (solvers/constraint_solver.hpp, RATTLE's own two solves). The integrators apply its Projection after each
// accepted step and count it (summary.json's projections); everything else is the model's.
#pragma once

#include <stepwise/models/model.hpp>

#include <memory>

namespace stepwise {

// the model with the projection (a model that offers DistanceConstraints)
std::unique_ptr<Model> projected(std::unique_ptr<Model> model);

}  // namespace stepwise
