#include "particle_mesh.hpp"

#include "solvers/capabilities/second_order.hpp"

#include "particle_common.hpp"
#include "plane_collision.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>

namespace stepwise {
namespace {

constexpr std::array particle_mesh_specs{
    ParamSpec{"count", 40, "", "number of particles N", Bound::positive},
    ParamSpec{"seed", 1, "", "random seed of the initial positions", Bound::nonnegative},
    ParamSpec{"spread", 0.6, "m", "particles start in [-spread, spread]^2 horizontally", Bound::positive},
    ParamSpec{"drop", 1.5, "m", "height of the bottom of the starting box", Bound::finite},
    ParamSpec{"restitution", 0.6, "", "coefficient of restitution eps of both surfaces", Bound::unit_interval},
    ParamSpec{"friction", 0.2, "", "Coulomb friction coefficient mu at impacts", Bound::nonnegative},
    ParamSpec{"g", 9.81, "m/s^2", "gravitational acceleration along -z", Bound::nonnegative},
    ParamSpec{"rest_speed", 0.05, "m/s", "a rebound slower than this ends in resting (sliding) contact", Bound::positive},
    ParamSpec{"plane_nx", 0.0, "", "ground plane normal, x component (normalised with the other two)", Bound::finite},
    ParamSpec{"plane_ny", 0.1, "", "ground plane normal, y component", Bound::finite},
    ParamSpec{"plane_nz", 1.0, "", "ground plane normal, z component", Bound::finite},
    ParamSpec{"plane_offset", 0.0, "m", "the ground is the plane n . p = offset (n normalised)", Bound::finite},
};

// per particle: the state in the integrators' copies and two events
constexpr double particle_mesh_bytes_per_particle = 32 * 6 * 8 + 2 * 256;

// a particle within this of a surface (m), moving along it slower than this (m/s), is resting on it: far
// above the round-off of sliding along a tilted face (1e-16 m per step) and above an adaptive code's error
// on the contact (measured with CVODE: at 1e-9 a particle resting on a mesh face fell out of contact and
// back 5 941 times in 3 s at rtol 1e-6; at 1e-7, once), far below any bounce
constexpr double contact_tolerance = 1e-7;

class ParticleMesh final : public Model, public EventSource {
 public:
  ParticleMesh(const Params& p, TriangleMesh mesh, std::vector<Plane> faces)
      : n_(particle_count(p, "count", particle_mesh_bytes_per_particle)), seed_(particle_seed(p)), spread_(p.at("spread")),
        drop_(p.at("drop")), eps_(p.at("restitution")), mu_(p.at("friction")), g_(p.at("g")),
        rest_speed_(p.at("rest_speed")), mesh_(std::move(mesh)), faces_(std::move(faces)) {
    const Eigen::Vector3d normal(p.at("plane_nx"), p.at("plane_ny"), p.at("plane_nz"));
    if (!(normal.norm() > 0))
      throw BadParameter("plane_nx", "parameters plane_nx, plane_ny, plane_nz: the ground plane's normal is zero");
    ground_ = make_plane(p.at("plane_offset") * normal.normalized(), normal);
    for (int i = 0; i < n_; ++i) {
      events_.push_back(Event{fmt::format("particle {} ground", i), -1,
                              [this, i](double, const Eigen::VectorXd& y) { return event_distance(y, i, ground_); },
                              [this, i](double, Eigen::VectorXd& y) { return collide(y, i, ground_); }});
      events_.push_back(Event{fmt::format("particle {} mesh", i), -1,
                              [this, i](double, const Eigen::VectorXd& y) { return event_distance(y, i, nearest_face(position(y, i))); },
                              [this, i](double, Eigen::VectorXd& y) { return collide(y, i, nearest_face(position(y, i))); }});
    }
  }

  std::string_view name() const override { return "particle-mesh"; }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    s.balls = particle_balls(y, n_);
    s.bodies.push_back({&mesh_});
    s.ground = ground_;
    return s;
  }
  int size() const override { return 6 * n_; }
  bool autonomous() const override { return true; }
  const void* capability(const std::type_info& type) const override { return offer(type, second_order_, as_part<EventSource>(*this)); }
  std::span<const Event> events() const override { return events_; }
  // the shortest return to a surface: a rebound at rest_speed along gravity, up and down
  double event_free_interval() const override { return g_ > 0 ? 2 * rest_speed_ / g_ : std::numeric_limits<double>::infinity(); }

  std::vector<std::string> state_names() const override { return particle_state_names(n_); }
  Eigen::VectorXd initial_state() const override {
    std::mt19937_64 rng(seed_);
    Eigen::VectorXd y = Eigen::VectorXd::Zero(6 * n_);
    for (int i = 0; i < n_; ++i) {
      y[3 * i] = spread_ * (2 * uniform01(rng) - 1);
      y[3 * i + 1] = spread_ * (2 * uniform01(rng) - 1);
      y[3 * i + 2] = drop_ + spread_ * uniform01(rng);
    }
    return y;
  }

  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    dydt.head(3 * n_) = y.tail(3 * n_);
    for (int i = 0; i < n_; ++i) {
      Eigen::Vector3d a(0, 0, -g_);
      // resting contact: the surface's normal force cancels what pushes into it
      const Eigen::Vector3d p = position(y, i), v = velocity(y, i);
      for (const Plane* face : {&ground_, &nearest_face(p)}) {
        if (resting(p, v, *face) && a.dot(face->normal) < 0) a -= a.dot(face->normal) * face->normal;
      }
      dydt.segment<3>(3 * n_ + 3 * i) = a;
    }
  }

  std::optional<double> energy(const Eigen::VectorXd& y) const override { return kinetic_and_gravity(y, g_); }

 private:
  static Eigen::Vector3d position(const Eigen::Ref<const Eigen::VectorXd>& y, int i) { return y.segment<3>(3 * i); }
  Eigen::Vector3d velocity(const Eigen::Ref<const Eigen::VectorXd>& y, int i) const { return y.segment<3>(3 * n_ + 3 * i); }

  // the face whose plane p is farthest in front of (for a point inside: the nearest face)
  const Plane& nearest_face(const Eigen::Vector3d& p) const {
    size_t best = 0;
    double d = signed_distance(faces_[0], p);
    for (size_t f = 1; f < faces_.size(); ++f)
      if (const double df = signed_distance(faces_[f], p); df > d) {
        d = df;
        best = f;
      }
    return faces_[best];
  }

  static bool resting(const Eigen::Vector3d& p, const Eigen::Vector3d& v, const Plane& face) {
    return std::abs(signed_distance(face, p)) <= contact_tolerance && std::abs(v.dot(face.normal)) <= contact_tolerance;
  }

  // the event function: the distance to the surface, held at 1 while the particle rests on it
  double event_distance(const Eigen::VectorXd& y, int i, const Plane& face) const {
    const Eigen::Vector3d p = position(y, i);
    return resting(p, velocity(y, i), face) ? 1.0 : signed_distance(face, p);
  }

  // particle i meets `face`: onto it, the plane response, and resting contact for a slow rebound
  std::string collide(Eigen::VectorXd& y, int i, const Plane& face) const {
    return plane_contact(face, y.segment<3>(3 * i), y.segment<3>(3 * n_ + 3 * i), eps_, mu_, rest_speed_);
  }

  int n_;
  unsigned long seed_;
  double spread_, drop_, eps_, mu_, g_, rest_speed_;
  TriangleMesh mesh_;  // the obstacle, as drawn
  std::vector<Plane> faces_;
  Plane ground_;
  std::vector<Event> events_;
  SecondOrderView second_order_{3 * n_};  // y = (x, v)
};

}  // namespace

std::span<const ParamSpec> particle_mesh_params() { return particle_mesh_specs; }

TriangleMesh default_obstacle() {
  TriangleMesh mesh;
  mesh.vertices.resize(6, 3);
  mesh.vertices << 0, 0, 0, 0, 0, 1, 0.5, 0, 0.5, -0.5, 0, 0.5, 0, 0.5, 0.5, 0, -0.5, 0.5;
  // vertices: 0 bottom, 1 top, 2 +x, 3 -x, 4 +y, 5 -y; faces counter-clockwise from outside
  mesh.faces.resize(8, 3);
  mesh.faces << 1, 2, 4, 1, 4, 3, 1, 3, 5, 1, 5, 2, 0, 4, 2, 0, 3, 4, 0, 5, 3, 0, 2, 5;
  return mesh;
}

std::unique_ptr<Model> make_particle_mesh(const Params& params, const TriangleMesh& mesh) {
  std::vector<Plane> faces;
  try {
    faces = convex_faces(mesh);
  } catch (const std::invalid_argument& e) {
    throw BadParameter("mesh", e.what());
  }
  return std::make_unique<ParticleMesh>(params, mesh, std::move(faces));
}

}  // namespace stepwise
