// Capability: rigid bodies that touch, each laid out as RigidBodyView's 13 entries (x, v, q, w with w in the
// body's principal frame), one after another, whose contacts are resolved at the velocity level by impulses
// rather than by forces in f (which then holds only the smooth forces: gravity, Euler's equations). The
// model finds the contacts (its geometry); the method resolves them (solvers/contact_solve.hpp, for
// sequential-impulses). A system offering it can be run by no method that does not resolve contacts.
#pragma once

#include <stepwise/solvers/ode_system.hpp>

#include <array>
#include <functional>
#include <utility>
#include <vector>

namespace stepwise {

// a contact at one point of two bodies, or of one body and the ground
struct Contact {
  int a = 0, b = -1;        // bodies; b = -1: the ground
  Eigen::Vector3d point;    // world (m)
  Eigen::Vector3d normal;   // unit, from b towards a: the direction a is pushed
  double depth = 0;         // penetration (m)
  std::array<int, 4> key{}; // (a, b, the body whose feature touches, the feature): the same contact from step to step
};

struct ContactMaterial {
  double restitution = 0;  // eps in [0, 1] at impacts
  double friction = 0;     // Coulomb's mu >= 0
  double resting_speed = 0;  // an approach no faster than this is resting contact: no bounce (m/s)
  double slop = 1e-4;      // penetration left alone (m)
  double push = 0.2;       // fraction of the rest pushed out per resolution
};

// a body's mass and principal moments, what the impulses need of it
struct BodyMass {
  double mass = 0;          // kg
  Eigen::Vector3d inertia;  // principal moments (kg m^2)
};

struct ContactBodiesView {
  std::vector<BodyMass> bodies;
  ContactMaterial material;  // its resting_speed is set per step from `g` (contact_solve.hpp)
  double g = 0;              // gravity (m/s^2): what one or two steps of it make is resting contact
  bool warm_start = true;    // a resolution starts from the last step's impulses at the same contacts
  // every contact of the bodies at y's configuration (the model's geometry)
  std::function<std::vector<Contact>(const Eigen::VectorXd& y)> find_contacts;
};

// what one resolution of contacts found and did
struct ContactOutcome {
  int impacts = 0;                 // pairs of bodies (or body and ground) meeting faster than a resting approach
  int sweeps = 0;                  // Gauss-Seidel sweeps over the contacts
  bool energy_guard = false;       // the frictional impulses would have raised the kinetic energy (measured):
                                   // the frictionless ones, which cannot, were applied instead
};

// the impulses of the last resolution of contacts, by contact key, which the next resolution starts from
// (warm start: resting contact changes little from step to step); the method keeps it between steps
struct ContactMemory {
  std::vector<std::pair<std::array<int, 4>, Eigen::Vector3d>> impulses;  // sorted by key
};

inline const Requirement needs_contact_bodies = needs<ContactBodiesView>("rigid bodies in contact (a contact scene)");

}  // namespace stepwise
