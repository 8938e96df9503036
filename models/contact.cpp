#include "contact.hpp"

#include "mass_properties.hpp"
#include "kernels/rigid_body.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

namespace stepwise {

namespace {

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
  // the vertices' extents along n, into vectors kept across the axes (no temporary a product per call)
  Eigen::VectorXd along_a(va.rows()), along_b(vb.rows());
  const auto overlap = [&](const Eigen::Vector3d& n) {
    along_a.noalias() = va * n;
    along_b.noalias() = vb * n;
    return along_a.maxCoeff() - along_b.minCoeff();
  };
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

std::vector<BodyMass> body_masses(std::span<const ContactBody> bodies) {
  std::vector<BodyMass> masses;
  for (const auto& body : bodies) masses.push_back({body.mass, body.inertia});
  return masses;
}

}  // namespace stepwise
