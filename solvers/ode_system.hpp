// The one thing every integrator sees: dy/dt = f(t, y); optional Jacobians, events and a projection are
// capabilities a system offers beside it.
//
// An integrator never includes a models/ header; a model implements this interface. Structure only some
// methods use (y = (x, v), a wave grid, a mass-spring network, bodies in contact, ...) is a capability: a
// plain type declared beside the methods that use it (solvers/capabilities/), which a model offers through
// capability() and a method asks for by type with as<T>().
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <cstddef>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <typeinfo>

namespace stepwise {

// An event g(t, y) = 0 (a collision, a plane crossing) and what happens at it.
struct Event {
  std::string name;                                                      // what the event is ("ground")
  int direction = 0;                                                     // +1: g rising through 0, -1: falling, 0: either
  std::function<double(double t, const Eigen::VectorXd& y)> g;          // root function
  // state change at the root (a collision response); returns what happened, as summary.json's events
  // write it ("impact", "rest"), or an empty string when nothing did (a crossing estimated too early,
  // where the state is still in front of the surface and moving away)
  std::function<std::string(double t, Eigen::VectorXd& y)> apply;
  // how a crossing is read: a surface (a built-in collision: a directed event is a wall the state may not end a
  // step behind, and a state found behind it fires at once), or a sign change (a user's event: it fires only
  // where g goes from one side of zero to the other in its direction, never from g = 0, so an event at t0 or
  // one just handled does not fire again)
  bool surface = true;
  // optional dg/dt along the solution (a sign-change event): where it changes sign within a step, g has an
  // extremum there, found and tested, so a step over a pair of roots (a graze, a flight shorter than the step)
  // still finds the first of them
  std::function<double(double t, const Eigen::VectorXd& y)> rate;
  bool terminal = false;     // the run ends at this event (with the state after its handler)
  bool keeps_state = false;  // the state just before and after the handler is kept (summary.json, trajectory.csv)
  bool may_rest = false;     // its handler can end the bouncing ("rest"): without one, it firing without bound is Zeno
};

class OdeSystem {
 public:
  virtual ~OdeSystem() = default;

  // dimension of y
  virtual int size() const = 0;

  // dydt = f(t, y); y and dydt have size() entries
  virtual void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const = 0;

  // true when f does not depend on t (then df/dt = 0)
  virtual bool autonomous() const { return false; }

  // the capability of this type the system offers (the optional parts below, solvers/capabilities/), or null; a
  // model answers with offer(), a method asks with as<T>()
  virtual const void* capability(const std::type_info& type) const { (void)type; return nullptr; }
  template <class Capability>
  const Capability* as() const { return static_cast<const Capability*>(capability(typeid(Capability))); }
};

// The optional parts of a system, each a capability: a model derives from the interface and offers itself as it
// (offer(type, as_part<DenseJacobian>(*this)), below), a method asks with system.as<DenseJacobian>().

// the analytic Jacobian df/dy, dense (size() x size())
class DenseJacobian {
 public:
  virtual ~DenseJacobian() = default;
  virtual void jacobian(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::MatrixXd> dfdy) const = 0;
};

// the Jacobian df/dy sparse, with a pattern that never changes (CSC); CVODE uses KLU with it
class SparseJacobian {
 public:
  virtual ~SparseJacobian() = default;
  virtual void sparse_jacobian(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::SparseMatrix<double>& dfdy) const = 0;
};

// a projection onto the manifold the exact flow keeps (a rigid body's unit quaternion, the ground a cloth may not
// pass): the integrators apply it after every accepted step (hand-written and GSL steppers; CVODE BDF through
// CVodeSetProjFn; CVODE Adams has none) and count it, keeping any multistep history (the correction is of the
// order of the local error)
class Projection {
 public:
  virtual ~Projection() = default;
  virtual void project(Eigen::Ref<Eigen::VectorXd> y) const = 0;
};

// events g(t, y) = 0 and what happens at them
class EventSource {
 public:
  virtual ~EventSource() = default;
  virtual std::span<const Event> events() const = 0;
  // the shortest time between two zeros of one event's g (a bouncing ball's shortest flight): adaptive
  // integrators step at most half of it, so a step never jumps over a pair of crossings and the ball
  // never passes through the floor unseen
  virtual double event_free_interval() const { return std::numeric_limits<double>::infinity(); }
};

// a system's events (none where it offers no EventSource) and their shortest event-free interval
inline std::span<const Event> events_of(const OdeSystem& system) {
  const auto* source = system.as<EventSource>();
  return source ? source->events() : std::span<const Event>{};
}
inline double event_free_interval_of(const OdeSystem& system) {
  const auto* source = system.as<EventSource>();
  return source ? source->event_free_interval() : std::numeric_limits<double>::infinity();
}

// a model's answer to capability(type): whichever of the capabilities it offers has that type, else null
template <class... Capabilities>
const void* offer(const std::type_info& type, const Capabilities&... offered) {
  const void* found = nullptr;
  ((found = found ? found : type == typeid(Capabilities) ? static_cast<const void*>(&offered) : nullptr), ...);
  return found;
}

// a system's own part (an interface it derives from: DenseJacobian, EventSource, ...) as offer() takes it:
// offer(type, second_order_, as_part<DenseJacobian>(*this))
template <class Part, class System>
const Part& as_part(const System& system) {
  return system;
}

// what a method needs of a system beyond f: one capability, by type, and what it is in words (for the
// message that refuses a system without it)
struct Requirement {
  const std::type_info* type = nullptr;  // null: nothing beyond f
  std::string_view what;                 // "a wave equation on a grid (a water scene)"
  bool offered_by(const OdeSystem& system) const { return !type || system.capability(*type) != nullptr; }
};
template <class Capability>
Requirement needs(std::string_view what) { return {&typeid(Capability), what}; }

}  // namespace stepwise
