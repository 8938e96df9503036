#include "ode_system.hpp"

#include <stdexcept>

namespace stepwise {

void OdeSystem::jacobian(double, const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::MatrixXd>) const {
  throw std::logic_error("OdeSystem::jacobian called on a system without an analytic Jacobian");
}

void OdeSystem::sparse_jacobian(double, const Eigen::Ref<const Eigen::VectorXd>&, Eigen::SparseMatrix<double>&) const {
  throw std::logic_error("OdeSystem::sparse_jacobian called on a system without a sparse Jacobian");
}

}  // namespace stepwise
