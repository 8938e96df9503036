// The one thing every integrator sees: dy/dt = f(t, y), with optional structure.
//
// An integrator never includes a models/ header; a model implements this interface.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <array>
#include <cstddef>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace stepwise {

// y = (x, v) with dx/dt = v: the layout symplectic steppers need.
struct SecondOrderView {
  int positions = 0;  // number of position coordinates n; y has 2n entries, x = y[0..n), v = y[n..2n)
};

// y = (z, v) on a square grid of points (boundary included, held at z = v = 0) for the damped wave
// equation d2z/dt2 = c^2 (5-point Laplacian of z) - mu dz/dt: the structure the seeds' three-level
// finite-difference scheme (wave_step.hpp) needs
struct WaveGridView {
  int points = 0;       // grid points per side; z = y[0..points^2) row-major, v = y[points^2..2 points^2)
  double spacing = 0;   // d (m)
  double c = 0;         // wave speed (m/s)
  double mu = 0;        // damping (1/s)
};

// the four neighbours of cell j of such a row-major grid with rows `n` apart, summed in one fixed order: the
// order every wave stencil keeps (the model's acceleration, the schemes' kernels, their float32 references),
// so that they agree to the bit where they compute the same thing
template <class T>
inline T neighbour_sum(const T* u, std::ptrdiff_t j, std::ptrdiff_t n) {
  return (u[j - n] + u[j + n]) + (u[j - 1] + u[j + 1]);
}

// y = (x, v, q, w) of one rigid body, 13 entries: position (3, m), velocity (3, m/s), orientation as a
// unit quaternion (w, x, y, z; body to world) and the angular velocity in the body's principal frame (3,
// rad/s); no torque, and a constant linear acceleration: the structure the splitting of the free rigid
// body into exact rotations needs (rigid_splitting.cpp)
struct RigidBodyView {
  Eigen::Vector3d inertia;       // principal moments I1, I2, I3 (kg m^2)
  Eigen::Vector3d acceleration;  // constant linear acceleration (m/s^2)
};

// y = `bodies` rigid bodies, each laid out as RigidBodyView's 13 entries (x, v, q, w with w in the body's
// principal frame), one after another, that touch: their contacts are resolved at the velocity level by
// impulses (OdeSystem::resolve_contacts), the structure a contact time-stepping method needs
struct ContactBodiesView {
  int bodies = 0;
};

// what one resolution of contacts found and did
struct ContactOutcome {
  int impacts = 0;                 // pairs of bodies (or body and ground) meeting faster than a resting approach
  int sweeps = 0;                  // Gauss-Seidel sweeps over the contacts
  bool energy_guard = false;       // the frictional impulses would have raised the kinetic energy (measured):
                                   // the frictionless ones, which cannot, were applied instead
};

// the impulses of the last resolution of contacts, by contact (a key the system chooses: the bodies and
// the feature that touches), which the next resolution starts from (warm start: resting contact changes
// little from step to step); the method keeps it between steps
struct ContactMemory {
  std::vector<std::pair<std::array<int, 4>, Eigen::Vector3d>> impulses;  // sorted by key
};

// a spring of a mass-spring network (seeds: Hooke's law with Voigt damping) between nodes a and b, or from
// the fixed point `anchor` to node b (a = -1: a pin); models/springs.hpp has its forces and derivatives
struct Spring {
  int a = -1, b = 0;                                 // node indices; a = -1: the fixed point `anchor`
  double rest = 1;                                   // l (m)
  double stiffness = 0;                              // c (N/m)
  double damping = 0;                                // gamma (N s/m)
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();  // where a pinned spring hangs from (m)
};

// y = (x, v) of `nodes` points in 3-D (x = y[0..3 nodes), node-major, then v), each with a lumped mass, so
// that M dv/dt = f(t, x, v) with M diagonal: the structure Baraff & Witkin's linearised implicit Euler on a
// sparse Cholesky factor, and the prefactored local/global method of Liu et al. 2013, need. The force
// Jacobians come from OdeSystem::force_jacobians; `springs` are the network's elastic springs, which the
// prefactored method treats implicitly (every other force, their damping included, it holds at the step's
// start)
struct MassSpringView {
  int nodes = 0;
  std::vector<double> mass;     // kg per node
  std::vector<Spring> springs;  // the springs whose elastic forces f holds
};

// y = (x, v) of a cloth: a rows x columns grid of nodes joined by the seeds' twelve springs (four each of
// structural: one apart along a row or column; shear: the diagonals; bend: two apart), with Voigt damping,
// lumped equal masses, linear drag, gravity along -y, a gusting wind through the normals of the grid's
// triangles, a constant force on one picked node, and a sphere and the ground as obstacles; y holds the
// free nodes (x node-major, then v), in grid order. The structure a node-parallel pass needs (each node
// gathering its own forces from its neighbours: the GPU cloth, solvers/cloth_grid.hpp), where
// MassSpringView's spring list is what a matrix assembly needs. Its forces are the model's (the model says
// how they are defined); cell (r, c)'s two triangles are (k, k + columns, k + 1) and
// (k + columns, k + columns + 1, k + 1), k = r columns + c
struct ClothGridView {
  int rows = 0, columns = 0;
  std::vector<Eigen::Vector3d> start;  // every grid node's starting place, row-major (a pinned node stays there)
  std::vector<int> free_index;         // grid node -> its node in y, -1 if pinned
  double across = 0, down = 0;         // rest lengths along a row and down a column (m)
  std::array<double, 3> stiffness{};   // structural, shear, bend c (N/m); a family switched off: no spring at all
  std::array<bool, 3> family{};        // which families are on
  double damping = 0;                  // gamma along every spring (N s/m)
  double node_mass = 0;                // kg
  double drag = 0;                     // 1/s
  double g = 0;                        // m/s^2, along -y
  Eigen::Vector3d wind = Eigen::Vector3d::Zero();  // w0 (m/s); w(t) = w0 (1 + gust_amplitude sin(2 pi gust_frequency t))
  double wind_coefficient = 0, gust_amplitude = 0, gust_frequency = 0;
  int picked = -1;                     // grid node the pick force pulls, -1 for none
  Eigen::Vector3d pick_force = Eigen::Vector3d::Zero();
  double sphere_radius = 0;            // 0: no sphere
  Eigen::Vector3d sphere_centre = Eigen::Vector3d::Zero();
  bool ground = false;
  double ground_y = 0, friction = 0;
};

// An event g(t, y) = 0 (a collision, a plane crossing) and what happens at it.
struct Event {
  std::string name;                                                      // what the event is ("ground")
  int direction = 0;                                                     // +1: g rising through 0, -1: falling, 0: either
  std::function<double(double t, const Eigen::VectorXd& y)> g;          // root function
  // state change at the root (a collision response); returns what happened, as summary.json's events
  // write it ("impact", "rest"), or an empty string when nothing did (a crossing estimated too early,
  // where the state is still in front of the surface and moving away)
  std::function<std::string(double t, Eigen::VectorXd& y)> apply;
};

class OdeSystem {
 public:
  virtual ~OdeSystem() = default;

  // dimension of y
  virtual int size() const = 0;

  // dydt = f(t, y); y and dydt have size() entries
  virtual void rhs(double t, Eigen::Ref<const Eigen::VectorXd> y, Eigen::Ref<Eigen::VectorXd> dydt) const = 0;

  // true when f does not depend on t (then df/dt = 0)
  virtual bool autonomous() const { return false; }

  // optional analytic Jacobian df/dy, dense (size() x size())
  virtual bool has_jacobian() const { return false; }
  virtual void jacobian(double t, Eigen::Ref<const Eigen::VectorXd> y, Eigen::Ref<Eigen::MatrixXd> dfdy) const;

  // optional sparse Jacobian with a pattern that never changes (CSC); CVODE uses KLU with it
  virtual bool has_sparse_jacobian() const { return false; }
  virtual void sparse_jacobian(double t, Eigen::Ref<const Eigen::VectorXd> y, Eigen::SparseMatrix<double>& dfdy) const;

  // optional second-order structure for symplectic steppers
  virtual std::optional<SecondOrderView> second_order() const { return std::nullopt; }

  // for a second-order system, a = dv/dt alone (the second half of f), which symplectic steppers need;
  // by default through rhs, and a large system (a particle system) gives it directly to save a pass
  virtual void acceleration(double t, Eigen::Ref<const Eigen::VectorXd> y, Eigen::Ref<Eigen::VectorXd> a) const;

  // true when each acceleration entry depends only on the same entries of x and v (a force field without
  // interactions): local_acceleration then gives a[first, first + count) from x and v over the same range,
  // so a stepper can sweep a large state once, in blocks that stay in cache, rather than in three passes
  virtual bool has_local_acceleration() const { return false; }
  virtual void local_acceleration(double t, const double* x, const double* v, double* a, Eigen::Index first,
                                  Eigen::Index count) const;

  // optional wave-equation structure for the finite-difference scheme
  virtual std::optional<WaveGridView> wave_grid() const { return std::nullopt; }

  // optional mass-spring structure (see MassSpringView): nullptr for a system without one
  virtual const MassSpringView* mass_spring() const { return nullptr; }
  // for a mass-spring system, the force Jacobians K = df/dx and D = df/dv (f = M dv/dt, 3 nodes x 3 nodes,
  // CSC, the same pattern at every call); definite: K replaced by a symmetric negative semidefinite
  // approximation and D by its symmetric part (the system says which), so that M - h D - h^2 K is symmetric
  // positive definite for a Cholesky factor; exact otherwise
  virtual void force_jacobians(double t, Eigen::Ref<const Eigen::VectorXd> y, bool definite, Eigen::SparseMatrix<double>& dfdx,
                               Eigen::SparseMatrix<double>& dfdv) const;

  // optional cloth-grid structure (see ClothGridView): nullptr for a system without one
  virtual const ClothGridView* cloth_grid() const { return nullptr; }

  // optional projection onto the manifold the exact flow keeps (a rigid body's unit quaternion): the
  // integrators apply it after every accepted step (hand-written and GSL steppers; CVODE BDF through
  // CVodeSetProjFn; CVODE Adams has no projection) and count it, keeping any multistep history (the
  // correction is of the order of the local error); returns false for a system without one
  virtual bool project(Eigen::Ref<Eigen::VectorXd> y) const { (void)y; return false; }

  // optional free-rigid-body structure for the splitting method
  virtual std::optional<RigidBodyView> free_rigid_body() const { return std::nullopt; }

  // optional rigid bodies in contact, resolved by impulses rather than by forces in f (which then holds
  // only the smooth forces: gravity, Euler's equations)
  virtual std::optional<ContactBodiesView> contact_bodies() const { return std::nullopt; }
  // the impulses at every contact of y's configuration that stop the bodies approaching there (with
  // restitution at impacts, Coulomb friction), applied to y's velocities, then y's positions moved out of
  // any penetration beyond a tolerance; dt is the step the velocities were advanced by (it sets what
  // approach counts as resting); memory carries the impulses from one call to the next
  virtual ContactOutcome resolve_contacts(Eigen::Ref<Eigen::VectorXd> y, double dt, ContactMemory& memory) const {
    (void)y;
    (void)dt;
    (void)memory;
    return {};
  }

  // optional events; an empty span means none
  virtual std::span<const Event> events() const { return {}; }

  // the shortest time between two zeros of one event's g (a bouncing ball's shortest flight): adaptive
  // integrators step at most half of it, so a step never jumps over a pair of crossings and the ball
  // never passes through the floor unseen
  virtual double event_free_interval() const { return std::numeric_limits<double>::infinity(); }
};

}  // namespace stepwise
