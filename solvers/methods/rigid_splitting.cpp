// `rigid-splitting`: the free rigid body's kinetic energy T = sum_k Pi_k^2 / (2 I_k) (Pi = I w, the body
// angular momentum) split into its three terms, each flowed exactly, and composed symmetrically
// (Strang): T1(h/2) T2(h/2) T3(h) T2(h/2) T1(h/2). The flow of T_k alone keeps Pi_k and rotates the body
// about its own axis k at the rate w_k = Pi_k / I_k: Pi(t) = R_k(-w_k t) Pi(0) and q(t) = q(0) (x) exp(w_k t e_k / 2),
// so each sub-step keeps the world angular momentum R Pi exactly (it is a rotation of the body against a
// rotation of Pi) and |Pi|; the composition is symplectic (Lie-Poisson) and of order 2, its energy error
// bounded for all time. McLachlan, "Explicit Lie-Poisson integration and the Euler equations", Phys. Rev.
// Lett. 71 (1993) 3043; Dullweber, Leimkuhler & McLachlan, "Symplectic splitting methods for rigid body
// molecular dynamics", J. Chem. Phys. 107 (1997) 5840. The centre of mass moves under its constant
// acceleration exactly.
#include "solvers/fixed_step.hpp"
#include "solvers/capabilities/free_rigid_body.hpp"
#include "solvers/run_support.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace stepwise {

namespace {

class RigidSplitting final : public FixedStepper {
 public:
  explicit RigidSplitting(const CountedSystem& s) : system_(s), body_(*s.as<RigidBodyView>()) {}

  bool step(double, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    ++system_.stats().rhs_evals;  // one evaluation's worth of work: the angular velocities, read from the state
    const Eigen::Vector3d x = y.segment<3>(0), v = y.segment<3>(3), a = body_.acceleration;
    y_next.segment<3>(0) = x + h * v + (h * h / 2) * a;
    y_next.segment<3>(3) = v + h * a;
    Eigen::Quaterniond q(y[6], y[7], y[8], y[9]);
    Eigen::Vector3d pi = body_.inertia.cwiseProduct(y.segment<3>(10));
    for (const auto& [axis, fraction] : {std::pair{0, 0.5}, {1, 0.5}, {2, 1.0}, {1, 0.5}, {0, 0.5}}) {
      const double angle = fraction * h * pi[axis] / body_.inertia[axis];
      // Pi turns by -angle in the plane of the other two axes (i, j) = (axis + 1, axis + 2), cyclic; the
      // body by +angle: q (x) (cos(angle/2), sin(angle/2) e_axis). One sine and cosine each, no matrices
      const int i = (axis + 1) % 3, j = (axis + 2) % 3;
      const double c = std::cos(angle), s = std::sin(angle);
      const double pi_i = pi[i], pi_j = pi[j];
      pi[i] = c * pi_i + s * pi_j;
      pi[j] = -s * pi_i + c * pi_j;
      Eigen::Quaterniond turn(std::cos(angle / 2), 0, 0, 0);
      turn.vec()[axis] = std::sin(angle / 2);
      q = q * turn;
    }
    y_next[6] = q.w();
    y_next[7] = q.x();
    y_next[8] = q.y();
    y_next[9] = q.z();
    y_next.segment<3>(10) = pi.cwiseQuotient(body_.inertia);
    return true;
  }

 private:
  const CountedSystem& system_;
  RigidBodyView body_;
};

}  // namespace

void register_rigid_splitting_methods(MethodTable& table) {
  table.add({
      .name = "rigid-splitting",
      .family = Family::rigid_splitting,
      .source = Source::hand_written,
      .description = "the free rigid body split into exact rotations about its principal axes, Strang-composed (symplectic, fixed step)",
      .order = {2, 2, "2"},
      .stepping = Stepping::fixed,
      .needs = needs_free_rigid_body,
      .make = fixed_steps([](const CountedSystem& system) { return std::make_unique<RigidSplitting>(system); }),
  });
}

}  // namespace stepwise
