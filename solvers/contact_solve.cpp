// The contact solve of sequential-impulses: projected Gauss-Seidel on accumulated impulses, warm started,
// with restitution, Coulomb friction and an energy guard, then the push out of penetration (the derivation
// is in contact_solve.hpp).
#include "contact_solve.hpp"

#include "kernels/rigid_body.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace stepwise {

namespace {

// world-frame velocities of every body, and the impulses that change them
struct Motion {
  std::span<const BodyMass> bodies;
  std::vector<Pose> poses;
  std::vector<Eigen::Matrix3d> inverse_inertia;  // world frame
  std::vector<Eigen::Vector3d> v, w;             // world frame

  Motion(std::span<const BodyMass> b, const Eigen::VectorXd& y) : bodies(b) {
    for (size_t i = 0; i < b.size(); ++i) {
      poses.push_back(pose(y, static_cast<int>(i)));
      const Eigen::Matrix3d& R = poses.back().R;
      inverse_inertia.push_back(R * b[i].inertia.cwiseInverse().asDiagonal() * R.transpose());
      v.push_back(y.segment<3>(13 * static_cast<int>(i) + 3));
      w.push_back(R * y.segment<3>(13 * static_cast<int>(i) + 10));
    }
  }
  Eigen::Vector3d arm(int body, const Eigen::Vector3d& point) const { return point - poses[static_cast<size_t>(body)].x; }
  // velocity of a's point relative to b's
  Eigen::Vector3d relative(const Contact& c) const {
    Eigen::Vector3d u = v[static_cast<size_t>(c.a)] + w[static_cast<size_t>(c.a)].cross(arm(c.a, c.point));
    if (c.b >= 0) u -= v[static_cast<size_t>(c.b)] + w[static_cast<size_t>(c.b)].cross(arm(c.b, c.point));
    return u;
  }
  Eigen::Matrix3d collision_matrix(const Contact& c) const {
    const auto part = [&](int body) -> Eigen::Matrix3d {
      Eigen::Matrix3d rx;
      const Eigen::Vector3d r = arm(body, c.point);
      rx << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
      return Eigen::Matrix3d::Identity() / bodies[static_cast<size_t>(body)].mass - rx * inverse_inertia[static_cast<size_t>(body)] * rx;
    };
    return c.b >= 0 ? Eigen::Matrix3d(part(c.a) + part(c.b)) : part(c.a);
  }
  void apply(const Contact& c, const Eigen::Vector3d& j) {
    const auto push = [&](int body, const Eigen::Vector3d& impulse) {
      const auto b = static_cast<size_t>(body);
      v[b] += impulse / bodies[b].mass;
      w[b] += inverse_inertia[b] * arm(body, c.point).cross(impulse);
    };
    push(c.a, j);
    if (c.b >= 0) push(c.b, -j);
  }
  double kinetic() const {
    double t = 0;
    for (size_t b = 0; b < v.size(); ++b) t += body_kinetic_energy(bodies[b].mass, bodies[b].inertia, v[b], poses[b].R.transpose() * w[b]);
    return t;
  }
  void store(Eigen::Ref<Eigen::VectorXd> y) const {
    for (size_t b = 0; b < v.size(); ++b) {
      y.segment<3>(13 * static_cast<int>(b) + 3) = v[b];
      y.segment<3>(13 * static_cast<int>(b) + 10) = poses[b].R.transpose() * w[b];
    }
  }
};

// Coulomb's law at one contact with tangential collision matrix Kt = Q diag(k) Q^T, for the sliding
// velocity `free` the contact would have without friction: the impulse that stops it, -Kt^-1 free, if it
// lies within the cone |lambda| <= limit; else the impulse on the cone's edge whose result slides exactly
// against it (maximal dissipation): (Kt + a 1) lambda = -free with a > 0 such that |lambda| = limit, then
// free + Kt lambda = a lambda points against lambda. Clamping the stopping impulse to the cone instead
// would turn the friction off the sliding direction wherever Kt is anisotropic (measured: a box sliding
// down a slope felt 6% less friction and a spurious yaw torque)
Eigen::Vector2d coulomb_friction(const Eigen::Matrix2d& Q, const Eigen::Vector2d& k, const Eigen::Vector2d& free, double limit) {
  const Eigen::Vector2d b = Q.transpose() * free;
  // squares as products, not std::pow(x, 2): the optimiser turns that into x * x while an unoptimised build
  // calls libm's pow, whose last bit may differ (measured: the contact collapse's frames differed between the
  // two builds from the first impact on)
  const auto squared_norm = [&](double a) {
    const double u0 = b[0] / (k[0] + a), u1 = b[1] / (k[1] + a);
    return u0 * u0 + u1 * u1;
  };
  if (squared_norm(0) <= limit * limit) return Q * Eigen::Vector2d(-b[0] / k[0], -b[1] / k[1]);
  if (!(limit > 0)) return Eigen::Vector2d::Zero();
  // phi(a) = 1/|lambda(a)| - 1/limit rises from below zero at a = 0 through zero by a = |b| / limit, and is
  // concave there: Newton's steps from the left (More & Sorensen's for the trust-region step) approach the
  // root from below, quadratically; bisection keeps them in the bracket against round-off
  double lo = 0, hi = b.norm() / limit, a = 0;
  for (int i = 0; i < 60; ++i) {
    const double n2 = squared_norm(a);
    const double phi = 1 / std::sqrt(n2) - 1 / limit;
    if (std::abs(phi) <= 1e-15 / limit) break;
    (phi < 0 ? lo : hi) = a;
    const double d0 = k[0] + a, d1 = k[1] + a;
    const double dn2 = -2 * (b[0] * b[0] / (d0 * d0 * d0) + b[1] * b[1] / (d1 * d1 * d1));
    const double next = a + phi / (0.5 * dn2 / (n2 * std::sqrt(n2)));
    a = (next > lo && next < hi) ? next : (lo + hi) / 2;
  }
  const Eigen::Vector2d lambda(-b[0] / (k[0] + a), -b[1] / (k[1] + a));
  return Q * (lambda * (limit / lambda.norm()));
}

}  // namespace

ContactOutcome resolve(std::span<const BodyMass> bodies, std::span<const Contact> contacts, const ContactMaterial& material,
                       Eigen::Ref<Eigen::VectorXd> y, ContactMemory& memory) {
  ContactOutcome outcome;
  if (contacts.empty()) {
    memory.impulses.clear();
    return outcome;
  }
  Motion motion(bodies, y);
  const Motion start = motion;
  const size_t n = contacts.size();
  struct Row {
    Eigen::Matrix3d K;
    Eigen::Matrix<double, 3, 2> tangents;
    Eigen::Matrix2d tangential;         // the collision matrix's tangential block T^T K T
    Eigen::Matrix2d tangential_axes;    // its eigenvectors ...
    Eigen::Vector2d tangential_moments; // ... and eigenvalues
    double normal_mass;   // n . K n
    double target;        // normal velocity wanted: -eps u_n at an impact, 0 otherwise
    double lambda_n = 0;
    Eigen::Vector2d lambda_t = Eigen::Vector2d::Zero();
  };
  std::vector<Row> rows(n);
  std::set<std::array<int, 2>> impact_pairs;
  for (size_t i = 0; i < n; ++i) {
    const Contact& c = contacts[i];
    Row& r = rows[i];
    r.K = motion.collision_matrix(c);
    const Eigen::Vector3d t1 = c.normal.unitOrthogonal();
    r.tangents << t1, c.normal.cross(t1);
    r.tangential = r.tangents.transpose() * r.K * r.tangents;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(r.tangential);
    r.tangential_axes = eigen.eigenvectors();
    r.tangential_moments = eigen.eigenvalues();
    r.normal_mass = c.normal.dot(r.K * c.normal);
    const double approach = -c.normal.dot(motion.relative(c));
    const bool impact = approach > material.resting_speed;
    r.target = impact ? material.restitution * approach : 0;
    if (impact) impact_pairs.insert({c.a, c.b});
  }
  outcome.impacts = static_cast<int>(impact_pairs.size());
  // warm start: a contact the last resolution had begins from its impulse there, inside this one's cone
  const auto key_less = [](const auto& entry, const std::array<int, 4>& key) { return entry.first < key; };
  for (size_t i = 0; i < n; ++i) {
    const Contact& c = contacts[i];
    const auto it = std::lower_bound(memory.impulses.begin(), memory.impulses.end(), c.key, key_less);
    if (it == memory.impulses.end() || it->first != c.key || rows[i].target > 0) continue;
    Row& r = rows[i];
    r.lambda_n = std::max(0.0, c.normal.dot(it->second));
    r.lambda_t = r.tangents.transpose() * it->second;
    if (const double limit = material.friction * r.lambda_n; r.lambda_t.norm() > limit) r.lambda_t *= limit / r.lambda_t.norm();
    motion.apply(c, r.lambda_n * c.normal + r.tangents * r.lambda_t);
  }
  for (outcome.sweeps = 1; outcome.sweeps <= contact_max_sweeps; ++outcome.sweeps) {
    double change = 0;
    for (size_t i = 0; i < n; ++i) {
      const Contact& c = contacts[i];
      Row& r = rows[i];
      const double lambda = std::max(0.0, r.lambda_n + (r.target - c.normal.dot(motion.relative(c))) / r.normal_mass);
      const double dn = lambda - r.lambda_n;
      r.lambda_n = lambda;
      motion.apply(c, dn * c.normal);
      change = std::max(change, std::abs(dn) * r.normal_mass);
      // the sliding velocity without this contact's friction, and the friction that stops it or, where that
      // lies outside the cone, the one on the cone's edge opposing the sliding that remains
      const Eigen::Vector2d free = r.tangents.transpose() * motion.relative(c) - r.tangential * r.lambda_t;
      const Eigen::Vector2d lambda_t = coulomb_friction(r.tangential_axes, r.tangential_moments, free, material.friction * r.lambda_n);
      const Eigen::Vector2d dt = lambda_t - r.lambda_t;
      r.lambda_t = lambda_t;
      const Eigen::Vector3d jt = r.tangents * dt;
      motion.apply(c, jt);
      change = std::max(change, (r.K * jt).norm());
    }
    if (change <= contact_velocity_tolerance) break;
  }
  outcome.sweeps = std::min(outcome.sweeps, contact_max_sweeps);
  if (motion.kinetic() > start.kinetic() * (1 + contact_energy_roundoff)) {
    // Gauss-Seidel with restitution and friction raised the energy: frictionless impulses, one contact at
    // a time, each of which cannot
    outcome.energy_guard = true;
    motion = start;
    for (int sweep = 0; sweep < contact_max_sweeps; ++sweep) {
      double change = 0;
      for (size_t i = 0; i < n; ++i) {
        const Contact& c = contacts[i];
        const double u_n = c.normal.dot(motion.relative(c));
        if (u_n >= 0) continue;
        const double eps = rows[i].target > 0 ? material.restitution : 0;
        motion.apply(c, -(1 + eps) * u_n / rows[i].normal_mass * c.normal);
        change = std::max(change, -(1 + eps) * u_n);
      }
      if (change <= contact_velocity_tolerance) break;
    }
  }
  motion.store(y);
  memory.impulses.clear();
  if (!outcome.energy_guard) {
    for (size_t i = 0; i < n; ++i) memory.impulses.emplace_back(contacts[i].key, rows[i].lambda_n * contacts[i].normal + rows[i].tangents * rows[i].lambda_t);
    std::sort(memory.impulses.begin(), memory.impulses.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
  }

  // push out what penetration the step left beyond the slop, along each pair's deepest contact
  std::map<std::array<int, 2>, const Contact*> deepest;
  for (const Contact& c : contacts) {
    const Contact*& d = deepest[{c.a, c.b}];
    if (!d || c.depth > d->depth) d = &c;
  }
  for (const auto& [pair, c] : deepest) {
    const double excess = c->depth - material.slop;
    // a pair separating faster than a resting approach clears its overlap by itself: left alone, so an
    // impact's momentum stays what the impulses made it
    if (excess <= 0 || c->normal.dot(motion.relative(*c)) > material.resting_speed) continue;
    const double wa = 1 / bodies[static_cast<size_t>(c->a)].mass, wb = c->b >= 0 ? 1 / bodies[static_cast<size_t>(c->b)].mass : 0;
    const Eigen::Vector3d shift = material.push * excess / (wa + wb) * c->normal;
    y.segment<3>(13 * c->a) += wa * shift;
    if (c->b >= 0) y.segment<3>(13 * c->b) -= wb * shift;
  }
  return outcome;
}

ContactOutcome resolve_contacts(const ContactBodiesView& view, Eigen::Ref<Eigen::VectorXd> y, double dt, ContactMemory& memory) {
  ContactMaterial material = view.material;
  // what one or two steps of gravity make is resting contact, not an impact to bounce from
  material.resting_speed = 2 * view.g * dt;
  const std::vector<Contact> contacts = view.find_contacts(y);
  if (!view.warm_start) memory.impulses.clear();
  return resolve(view.bodies, contacts, material, y, memory);
}

}  // namespace stepwise
