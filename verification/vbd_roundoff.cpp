#include "vbd_roundoff.hpp"

namespace stepwise {

double gradient_scale(const IncrementalPotential& G, const MassSpringView& view, const Eigen::VectorXd& x) {
  const int d = view.dimension;
  const Eigen::VectorXd e = x - G.inertial();
  Eigen::VectorXd s = (e.cwiseAbs().cwiseProduct(G.mass()) / (G.h() * G.h()) + G.damping().cwiseAbs() * e.cwiseAbs() / G.h() + G.other_forces().cwiseAbs())
                          .reshaped(d, view.nodes)
                          .colwise()
                          .sum()
                          .transpose();
  const auto at = [&](int node, const Eigen::Vector3d& anchor) {
    Eigen::Vector3d p = anchor;
    if (node >= 0) p.head(d) = x.segment(Eigen::Index{d} * node, d);
    return p;
  };
  for (const Spring& spring : view.springs) {
    const Eigen::Vector3d a = at(spring.a, spring.anchor), b = at(spring.b, spring.anchor);
    const double term = spring.stiffness * (std::abs((b - a).norm() - spring.rest) + (b - a).norm() + a.norm() + b.norm());
    for (const int node : {spring.a, spring.b})
      if (node >= 0) s[node] += term;
  }
  return s.norm();
}

}  // namespace stepwise
