#include "fd_jacobian.hpp"

#include <cmath>
#include <limits>

namespace stepwise {

void fd_jacobian(const OdeSystem& system, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                 Eigen::Ref<Eigen::MatrixXd> dfdy) {
  const int n = system.size();
  const double cbrt_eps = std::cbrt(std::numeric_limits<double>::epsilon());
  Eigen::VectorXd yp = y, fp(n), fm(n);
  for (int j = 0; j < n; ++j) {
    const double d = cbrt_eps * std::max(1.0, std::abs(y[j]));
    yp[j] = y[j] + d;
    system.rhs(t, yp, fp);
    yp[j] = y[j] - d;
    system.rhs(t, yp, fm);
    yp[j] = y[j];
    dfdy.col(j) = (fp - fm) / (2 * d);
  }
}

void jacobian_or_fd(const OdeSystem& system, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                    Eigen::Ref<Eigen::MatrixXd> dfdy) {
  if (const auto* analytic = system.as<DenseJacobian>()) analytic->jacobian(t, y, dfdy);
  else fd_jacobian(system, t, y, dfdy);
}

}  // namespace stepwise
