// `sequential-impulses`: time stepping for rigid bodies in contact, the velocity-level scheme animation
// uses (Moreau's sweeping process as Stewart & Trinkle, "An implicit time-stepping scheme for rigid body
// dynamics with inelastic collisions and Coulomb friction", IJNME 39, 1996, set it up; solved by
// sequential impulses as in Catto, "Iterative dynamics with temporal coherence", GDC 2005). One step of h:
//   kick      v += h dv/dt, w += h dw/dt            (the smooth forces of f: gravity, Euler's equations)
//   contacts  the impulses at the contacts the model finds at the step's start positions (restitution at
//             impacts, Coulomb friction), then the push out of penetration (contact_solve.hpp)
//   drift     x += h v, q = q (x) exp(h w / 2)       (the rotation at the new body rate, exact for it)
// Without contacts this is symplectic Euler on the translation; order 1.
#include "solvers/contact_solve.hpp"
#include "solvers/fixed_step.hpp"
#include "solvers/run_support.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace stepwise {

namespace {

class ContactStepping final : public FixedStepper {
 public:
  explicit ContactStepping(const CountedSystem& s)
      : system_(s), view_(*s.as<ContactBodiesView>()), bodies_(static_cast<int>(view_.bodies.size())), f_(s.size()) {}

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    system_.rhs(t, y, f_);
    y_next = y;
    for (int b = 0; b < bodies_; ++b) {
      const int o = 13 * b;
      y_next.segment<3>(o + 3) += h * f_.segment<3>(o + 3);
      y_next.segment<3>(o + 10) += h * f_.segment<3>(o + 10);
    }
    const ContactOutcome outcome = resolve_contacts(view_, y_next, h, memory_);
    impacts_ += outcome.impacts;
    system_.stats().contact_sweeps += outcome.sweeps;
    for (int b = 0; b < bodies_; ++b) {
      const int o = 13 * b;
      y_next.segment<3>(o) += h * y_next.segment<3>(o + 3);
      const Eigen::Vector3d w = y_next.segment<3>(o + 10);
      const double angle = h * w.norm();
      if (angle > 0) {
        Eigen::Quaterniond turn;
        turn.w() = std::cos(angle / 2);
        turn.vec() = std::sin(angle / 2) * w.normalized();
        const Eigen::Quaterniond q = Eigen::Quaterniond(y_next[o + 6], y_next[o + 7], y_next[o + 8], y_next[o + 9]) * turn;
        y_next.segment<4>(o + 6) << q.w(), q.x(), q.y(), q.z();
      }
    }
    return true;
  }

  void reset() override { memory_.impulses.clear(); }

  bool handles_events() const override { return true; }
  void take_events(std::vector<std::string>& kinds) override {
    kinds.assign(static_cast<size_t>(impacts_), "impact");
    impacts_ = 0;
  }

 private:
  const CountedSystem& system_;
  const ContactBodiesView& view_;
  int bodies_;
  Eigen::VectorXd f_;
  long impacts_ = 0;
  ContactMemory memory_;  // last step's impulses, the next step's warm start
};

}  // namespace

void register_sequential_impulses_methods(MethodTable& table) {
  table.add({
      .name = "sequential-impulses",
      .family = Family::sequential_impulses,
      .source = Source::hand_written,
      .description = "rigid bodies in contact: kick, contact impulses by projected Gauss-Seidel (restitution, Coulomb "
                     "friction), drift (velocity-level time stepping, fixed step)",
      .order = {1, 1, "1"},
      .stepping = Stepping::fixed,
      .needs = needs_contact_bodies,
      .make = fixed_steps([](const CountedSystem& system) { return std::make_unique<ContactStepping>(system); }),
  });
}

}  // namespace stepwise
