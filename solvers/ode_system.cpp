#include "ode_system.hpp"

#include <stdexcept>

namespace stepwise {

void OdeSystem::jacobian(double, Eigen::Ref<const Eigen::VectorXd>, Eigen::Ref<Eigen::MatrixXd>) const {
  throw std::logic_error("OdeSystem::jacobian called on a system without an analytic Jacobian");
}

void OdeSystem::sparse_jacobian(double, Eigen::Ref<const Eigen::VectorXd>, Eigen::SparseMatrix<double>&) const {
  throw std::logic_error("OdeSystem::sparse_jacobian called on a system without a sparse Jacobian");
}

void OdeSystem::force_jacobians(double, Eigen::Ref<const Eigen::VectorXd>, bool, Eigen::SparseMatrix<double>&,
                                Eigen::SparseMatrix<double>&) const {
  throw std::logic_error("OdeSystem::force_jacobians called on a system without a mass-spring structure");
}

void OdeSystem::acceleration(double t, Eigen::Ref<const Eigen::VectorXd> y, Eigen::Ref<Eigen::VectorXd> a) const {
  const auto view = second_order();
  if (!view) throw std::logic_error("OdeSystem::acceleration called on a first-order system");
  Eigen::VectorXd f(size());
  rhs(t, y, f);
  a = f.tail(view->positions);
}

void OdeSystem::local_acceleration(double, const double*, const double*, double*, Eigen::Index, Eigen::Index) const {
  throw std::logic_error("OdeSystem::local_acceleration called on a system without a local acceleration");
}

}  // namespace stepwise
