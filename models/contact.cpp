#include "contact.hpp"

#include "mass_properties.hpp"
#include "rigid_body.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

namespace stepwise {

namespace {

struct Pose {
  Eigen::Vector3d x;
  Eigen::Matrix3d R;  // body to world
};

Pose pose(const Eigen::VectorXd& y, int body) {
  const int o = 13 * body;
  return {y.segment<3>(o), Eigen::Quaterniond(y[o + 6], y[o + 7], y[o + 8], y[o + 9]).normalized().toRotationMatrix()};
}

// largest signed distance of p (body frame) to the body's face planes: negative inside
double face_distance(const ContactBody& body, const Eigen::Vector3d& p) {
  double d = -std::numeric_limits<double>::infinity();
  for (const Plane& face : body.faces) d = std::max(d, signed_distance(face, p));
  return d;
}

std::vector<int> unique_sorted(std::vector<int> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

struct FeaturePoint {
  Eigen::Vector3d point;  // world
  int feature;            // a vertex index, or the number of vertices plus a feature edge's index
};

// the points of `other`'s features (vertices and feature edges of the faces listed) inside `body`, both
// given in body's frame, appended to `out` in the world frame
void features_inside(const ContactBody& body, const Pose& body_pose, const ContactBody& other,
                     const Eigen::Matrix<double, Eigen::Dynamic, 3>& other_here, std::span<const int> other_faces,
                     std::span<const int> body_faces, std::vector<FeaturePoint>& out) {
  const auto inside = [&](const Eigen::Vector3d& p) { return face_distance(body, p) < 0; };
  std::vector<int> vertices;
  std::vector<int> edges;
  for (const int f : other_faces)
    for (int k = 0; k < 3; ++k) {
      vertices.push_back(other.mesh.faces(f, k));
      if (const int e = other.face_edges[static_cast<size_t>(f)][static_cast<size_t>(k)]; e >= 0) edges.push_back(e);
    }
  for (const int v : unique_sorted(std::move(vertices)))
    if (const Eigen::Vector3d p = other_here.row(v).transpose(); inside(p)) out.push_back({body_pose.x + body_pose.R * p, v});
  // an edge crossing the body with both ends outside: the middle of the part inside
  for (const int e : unique_sorted(std::move(edges))) {
    const Eigen::Vector3d p0 = other_here.row(other.edges[static_cast<size_t>(e)][0]).transpose();
    const Eigen::Vector3d p1 = other_here.row(other.edges[static_cast<size_t>(e)][1]).transpose();
    if (inside(p0) || inside(p1)) continue;
    double lo = 1, hi = 0;
    for (const int f : body_faces)
      if (const auto s = segment_triangle(p0, p1, triangle(body.mesh, f))) {
        lo = std::min(lo, *s);
        hi = std::max(hi, *s);
      }
    if (const Eigen::Vector3d mid = p0 + (lo + hi) / 2 * (p1 - p0); hi > lo && inside(mid))
      out.push_back({body_pose.x + body_pose.R * mid, static_cast<int>(other_here.rows()) + e});
  }
}

// the vertices of `body` at pose `at`, in the frame of pose `frame` (the world's when none)
Eigen::Matrix<double, Eigen::Dynamic, 3> vertices_in(const ContactBody& body, const Pose& at, const Pose* frame = nullptr) {
  const Eigen::Matrix3d R = frame ? Eigen::Matrix3d(frame->R.transpose() * at.R) : at.R;
  const Eigen::Vector3d t = frame ? Eigen::Vector3d(frame->R.transpose() * (at.x - frame->x)) : at.x;
  return (body.mesh.vertices * R.transpose()).rowwise() + t.transpose();
}

// the separating-axis test's axis of least overlap between two convex bodies that touch (Gottschalk, Lin
// & Manocha, "OBBTree", SIGGRAPH 1996; Ericson 5.2.1): among the face normals of both and the cross
// products of their feature edges, the direction n (from a towards b) along which b must move least to
// clear a, and that distance, max_a n.p - min_b n.p. A face axis is kept over an edge axis unless the
// edge's overlap is clearly smaller, so that face-face contact keeps the face's normal
std::pair<Eigen::Vector3d, double> least_overlap(const ContactBody& a, const Pose& pa, const ContactBody& b, const Pose& pb) {
  const auto va = vertices_in(a, pa), vb = vertices_in(b, pb);
  const auto overlap = [&](const Eigen::Vector3d& n) { return (va * n).maxCoeff() - (vb * n).minCoeff(); };
  Eigen::Vector3d best_axis = Eigen::Vector3d::UnitZ();
  double best = std::numeric_limits<double>::infinity();
  const auto consider = [&](const Eigen::Vector3d& n, double preference) {
    if (const double d = overlap(n); d * preference < best) {
      best = d * preference;
      best_axis = n;
    }
  };
  for (const Plane& f : a.faces) consider(pa.R * f.normal, 1);
  for (const Plane& f : b.faces) consider(-(pb.R * f.normal), 1);
  const Eigen::Vector3d between = pb.x - pa.x;
  for (const auto& ea : a.edges) {
    const Eigen::Vector3d da = pa.R * (a.mesh.vertices.row(ea[1]) - a.mesh.vertices.row(ea[0])).transpose().normalized();
    for (const auto& eb : b.edges) {
      const Eigen::Vector3d db = pb.R * (b.mesh.vertices.row(eb[1]) - b.mesh.vertices.row(eb[0])).transpose().normalized();
      Eigen::Vector3d n = da.cross(db);
      if (n.norm() < 1e-6) continue;  // parallel edges: their plane's normal is a face axis already
      n.normalize();
      consider(n.dot(between) < 0 ? Eigen::Vector3d(-n) : n, 1.05);
    }
  }
  return {best_axis, overlap(best_axis)};
}

}  // namespace

ContactBody make_contact_body(const TriangleMesh& mesh, double density, MeshPlacement* placement) {
  const MassProperties props = mass_properties(mesh, density);
  const PrincipalFrame frame = principal_frame(props.inertia);
  ContactBody body;
  body.mesh = mesh;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    body.mesh.vertices.row(v) = (frame.axes.transpose() * (mesh.vertices.row(v).transpose() - props.center)).transpose();
  body.faces = convex_faces(body.mesh);  // convex, with outward faces: or throws naming what is not
  body.bvh = build_bvh(body.mesh);
  body.mass = props.mass;
  body.inertia = frame.moments;
  body.radius = body.mesh.vertices.rowwise().norm().maxCoeff();
  // feature edges: between two faces whose planes differ (a box face's diagonal is not one)
  std::map<std::array<int, 2>, std::vector<int>> faces_of_edge;
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int u = mesh.faces(f, k), w = mesh.faces(f, (k + 1) % 3);
      faces_of_edge[{std::min(u, w), std::max(u, w)}].push_back(static_cast<int>(f));
    }
  std::map<std::array<int, 2>, int> index;
  for (const auto& [edge, faces] : faces_of_edge)
    if (body.faces[static_cast<size_t>(faces[0])].normal.dot(body.faces[static_cast<size_t>(faces[1])].normal) < 1 - 1e-9) {
      index[edge] = static_cast<int>(body.edges.size());
      body.edges.push_back(edge);
    }
  body.face_edges.resize(static_cast<size_t>(mesh.faces.rows()));
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int u = mesh.faces(f, k), w = mesh.faces(f, (k + 1) % 3);
      const auto it = index.find({std::min(u, w), std::max(u, w)});
      body.face_edges[static_cast<size_t>(f)][static_cast<size_t>(k)] = it == index.end() ? -1 : it->second;
    }
  if (placement) *placement = MeshPlacement{frame.axes, props.center};
  return body;
}

std::vector<Contact> find_contacts(std::span<const ContactBody> bodies, const Plane* ground, const Eigen::VectorXd& y, long* exact_tests) {
  std::vector<Contact> contacts;
  const int n = static_cast<int>(bodies.size());
  std::vector<Pose> poses;
  for (int i = 0; i < n; ++i) poses.push_back(pose(y, i));
  for (int i = 0; i < n; ++i) {
    const ContactBody& body = bodies[static_cast<size_t>(i)];
    const Pose& p = poses[static_cast<size_t>(i)];
    if (ground && signed_distance(*ground, p.x) < body.radius)
      for (Eigen::Index v = 0; v < body.mesh.vertices.rows(); ++v) {
        const Eigen::Vector3d point = p.x + p.R * body.mesh.vertices.row(v).transpose();
        if (const double d = signed_distance(*ground, point); d < 0)
          contacts.push_back(Contact{i, -1, point, ground->normal, -d, {i, -1, i, static_cast<int>(v)}});
      }
    for (int j = i + 1; j < n; ++j) {
      const ContactBody& other = bodies[static_cast<size_t>(j)];
      const Pose& q = poses[static_cast<size_t>(j)];
      if ((p.x - q.x).norm() > body.radius + other.radius) continue;
      // the other's mesh in this body's frame, and the face pairs that cut each other
      TriangleMesh other_here{vertices_in(other, q, &p), other.mesh.faces};
      const PairQuery query = intersecting_pairs(body.mesh, body.bvh, other_here, build_bvh(other_here));
      if (exact_tests) *exact_tests += query.exact_tests;
      if (query.pairs.empty()) continue;
      std::vector<int> mine, theirs;
      for (const auto& [f, g] : query.pairs) {
        mine.push_back(f);
        theirs.push_back(g);
      }
      mine = unique_sorted(std::move(mine));
      theirs = unique_sorted(std::move(theirs));
      std::vector<FeaturePoint> theirs_inside, mine_inside;
      features_inside(body, p, other, other_here.vertices, theirs, mine, theirs_inside);
      features_inside(other, q, body, vertices_in(body, p, &q), mine, theirs, mine_inside);
      if (theirs_inside.empty() && mine_inside.empty()) continue;
      // one normal for the pair's whole manifold: the axis of least overlap, pushing the other body away
      const auto [normal, depth] = least_overlap(body, p, other, q);
      for (const auto& f : theirs_inside) contacts.push_back(Contact{j, i, f.point, normal, depth, {j, i, j, f.feature}});
      for (const auto& f : mine_inside) contacts.push_back(Contact{j, i, f.point, normal, depth, {j, i, i, f.feature}});
    }
  }
  return contacts;
}

double kinetic_energy(std::span<const ContactBody> bodies, const Eigen::VectorXd& y) {
  double t = 0;
  for (size_t b = 0; b < bodies.size(); ++b) {
    const int o = 13 * static_cast<int>(b);
    t += body_kinetic_energy(bodies[b].mass, bodies[b].inertia, y.segment<3>(o + 3), y.segment<3>(o + 10));
  }
  return t;
}

namespace {

// world-frame velocities of every body, and the impulses that change them
struct Motion {
  std::span<const ContactBody> bodies;
  std::vector<Pose> poses;
  std::vector<Eigen::Matrix3d> inverse_inertia;  // world frame
  std::vector<Eigen::Vector3d> v, w;             // world frame

  Motion(std::span<const ContactBody> b, const Eigen::VectorXd& y) : bodies(b) {
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
  const auto squared_norm = [&](double a) { return std::pow(b[0] / (k[0] + a), 2) + std::pow(b[1] / (k[1] + a), 2); };
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
    const double dn2 = -2 * (std::pow(b[0], 2) / std::pow(k[0] + a, 3) + std::pow(b[1], 2) / std::pow(k[1] + a, 3));
    const double next = a + phi / (0.5 * dn2 / (n2 * std::sqrt(n2)));
    a = (next > lo && next < hi) ? next : (lo + hi) / 2;
  }
  const Eigen::Vector2d lambda(-b[0] / (k[0] + a), -b[1] / (k[1] + a));
  return Q * (lambda * (limit / lambda.norm()));
}

}  // namespace

ContactOutcome resolve(std::span<const ContactBody> bodies, std::span<const Contact> contacts, const ContactMaterial& material,
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

}  // namespace stepwise
