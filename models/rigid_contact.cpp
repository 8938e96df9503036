#include "rigid_contact.hpp"

#include "contact.hpp"
#include "particle_common.hpp"
#include "rigid_body.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <cmath>
#include <numbers>

namespace stepwise {

namespace {

// a model's own parameters, then those of the contacts (their defaults per model), gravity and the ground
std::vector<ParamSpec> with_contact_params(std::vector<ParamSpec> own, double restitution, double friction) {
  own.insert(own.end(), {
      {"g", 9.81, "m/s^2", "gravitational acceleration, along -z", Bound::nonnegative},
      {"restitution", restitution, "", "coefficient of restitution eps at impacts", Bound::unit_interval},
      {"friction", friction, "", "Coulomb friction coefficient mu", Bound::nonnegative},
      {"ground_slope", 0.0, "rad", "the ground turned about the y axis (|slope| < pi/2)"},
      {"ground", 1.0, "", "1: the ground plane is there; 0: no ground (bodies meet only each other)", Bound::flag},
      {"push", 0.2, "", "fraction of a resting pair's penetration (beyond 0.1 mm) pushed out per step; positions only", Bound::unit_interval},
      {"warm_start", 1.0, "", "1: Gauss-Seidel starts from the last step's impulses; 0: from zero", Bound::flag},
  });
  return own;
}

// one body's start: its shape and its 13-entry state
struct Placed {
  ContactBody body;
  Eigen::VectorXd state;
};

// the body of `mesh` at centre of mass x, the mesh turned by q (mesh frame to world), with velocity v and
// world angular velocity w
Placed place(const TriangleMesh& mesh, double density, const Eigen::Vector3d& x, const Eigen::Quaterniond& q,
             const Eigen::Vector3d& v, const Eigen::Vector3d& w) {
  MeshPlacement frame;
  Placed p{make_contact_body(mesh, density, &frame), Eigen::VectorXd(13)};
  // body (principal) axes to world: q times the principal axes in the mesh frame
  const Eigen::Quaterniond body = (q * Eigen::Quaterniond(frame.axes)).normalized();
  p.state << x, v, body.w(), body.x(), body.y(), body.z(), body.conjugate() * w;
  return p;
}

std::optional<Plane> ground(const Params& p) {
  if (p.at("ground") == 0) return std::nullopt;
  const double s = p.at("ground_slope");
  if (!(std::abs(s) < std::numbers::pi / 2))
    throw BadParameter("ground_slope", fmt::format("parameter 'ground_slope' must lie in (-pi/2, pi/2), got {}", s));
  return make_plane(Eigen::Vector3d::Zero(), Eigen::Vector3d(std::sin(s), 0, std::cos(s)));
}

class RigidContact final : public Model, public Projection {
 public:
  RigidContact(std::string_view name, std::vector<Placed> placed, const Params& p)
      : name_(name), ground_(ground(p)), g_(p.at("g")) {
    y0_.resize(13 * static_cast<Eigen::Index>(placed.size()));
    for (size_t i = 0; i < placed.size(); ++i) {
      y0_.segment<13>(13 * static_cast<Eigen::Index>(i)) = placed[i].state;
      bodies_.push_back(std::move(placed[i].body));
    }
    contact_.bodies = body_masses(bodies_);
    contact_.material.restitution = p.at("restitution");
    contact_.material.friction = p.at("friction");
    contact_.material.push = p.at("push");
    contact_.g = g_;
    contact_.warm_start = p.at("warm_start") == 1;
    contact_.find_contacts = [this](const Eigen::VectorXd& y) { return find_contacts(bodies_, ground_ ? &*ground_ : nullptr, y); };
  }
  RigidContact(const RigidContact&) = delete;  // contact_ holds `this`
  RigidContact& operator=(const RigidContact&) = delete;

  std::string_view name() const override { return name_; }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    for (size_t b = 0; b < bodies_.size(); ++b) {
      const Eigen::Index o = 13 * static_cast<Eigen::Index>(b);
      const Eigen::Quaterniond q(y[o + 6], y[o + 7], y[o + 8], y[o + 9]);
      s.bodies.push_back({&bodies_[b].mesh, q.normalized().toRotationMatrix(), y.segment<3>(o)});
    }
    s.ground = ground_;
    return s;
  }
  int size() const override { return static_cast<int>(y0_.size()); }
  bool autonomous() const override { return true; }
  std::vector<std::string> state_names() const override { return rigid_body_state_names(static_cast<int>(bodies_.size())); }
  Eigen::VectorXd initial_state() const override { return y0_; }

  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    for (size_t b = 0; b < bodies_.size(); ++b) {
      const Eigen::Index o = 13 * static_cast<Eigen::Index>(b);
      dydt.segment<3>(o) = y.segment<3>(o + 3);
      dydt.segment<3>(o + 3) = Eigen::Vector3d(0, 0, -g_);
      free_rotation_rates(bodies_[b].inertia, y.segment<13>(o), dydt.segment<13>(o));
    }
  }

  void project(Eigen::Ref<Eigen::VectorXd> y) const override {
    for (size_t b = 0; b < bodies_.size(); ++b) y.segment<4>(13 * static_cast<Eigen::Index>(b) + 6).normalize();
  }

  const void* capability(const std::type_info& type) const override { return offer(type, contact_, as_part<Projection>(*this)); }

  std::optional<double> energy(const Eigen::VectorXd& y) const override {
    double potential = 0;
    for (size_t b = 0; b < bodies_.size(); ++b) potential += bodies_[b].mass * g_ * y[13 * static_cast<Eigen::Index>(b) + 2];
    return kinetic_energy(bodies_, y) + potential;
  }

  std::vector<std::string> summary_names() const override {
    auto names = state_names();
    names.insert(names.end(), {"energy", "kinetic", "px", "py", "pz", "Lx", "Ly", "Lz"});
    return names;
  }
  Eigen::VectorXd summary(const Eigen::VectorXd& y) const override {
    Eigen::Vector3d momentum = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
    for (size_t b = 0; b < bodies_.size(); ++b) {
      const Eigen::Index o = 13 * static_cast<Eigen::Index>(b);
      const Eigen::Vector3d p = bodies_[b].mass * y.segment<3>(o + 3);
      momentum += p;
      angular += y.segment<3>(o).cross(p) + body_angular_momentum(bodies_[b].inertia, y.segment<13>(o));
    }
    Eigen::VectorXd s(y.size() + 8);
    s << y, *energy(y), kinetic_energy(bodies_, y), momentum, angular;
    return s;
  }

 private:
  std::string_view name_;
  std::vector<ContactBody> bodies_;
  std::optional<Plane> ground_;
  double g_;
  ContactBodiesView contact_;  // the bodies' masses, their material, and the model's contact detection
  Eigen::VectorXd y0_;
};

}  // namespace

// function-local: the model table, built at static initialisation in another file, asks for them
std::span<const ParamSpec> dropped_body_params() {
  // defaults: the tumbling-box scene's drop, turned 45 degrees about x so that an edge lands first
  static const std::vector<ParamSpec> params = with_contact_params(
      {
          {"hx", 0.3, "m", "box half-extent along x (without a [mesh])", Bound::positive},
          {"hy", 0.2, "m", "box half-extent along y", Bound::positive},
          {"hz", 0.1, "m", "box half-extent along z", Bound::positive},
          {"density", 500.0, "kg/m^3", "uniform density", Bound::positive},
          {"x0", 0.0, "m", "initial centre of mass x"},
          {"y0", 0.0, "m", "initial centre of mass y"},
          {"z0", 1.5, "m", "initial centre of mass z (height)"},
          {"vx0", 0.5, "m/s", "initial velocity x"},
          {"vy0", 0.0, "m/s", "initial velocity y"},
          {"vz0", 0.0, "m/s", "initial velocity z"},
          {"qw0", 0.9238795325112867, "", "initial orientation of the box or mesh as given, quaternion scalar part (normalised; not all four zero)"},
          {"qx0", 0.3826834323650898, "", "initial orientation quaternion, x"},
          {"qy0", 0.0, "", "initial orientation quaternion, y"},
          {"qz0", 0.0, "", "initial orientation quaternion, z"},
          {"wx0", 1.0, "rad/s", "initial angular velocity, world x"},
          {"wy0", 4.0, "rad/s", "initial angular velocity, world y"},
          {"wz0", 2.0, "rad/s", "initial angular velocity, world z"},
      },
      0.4, 0.5);
  return params;
}

std::span<const ParamSpec> box_stack_params() {
  static const std::vector<ParamSpec> params = with_contact_params(
      {
          {"rows", 5, "", "boxes in each column of the wall", Bound::positive},
          {"columns", 3, "", "columns of the wall, side by side along y", Bound::positive},
          {"hx", 0.2, "m", "box half-extent along x (the wall's thickness)", Bound::positive},
          {"hy", 0.2, "m", "box half-extent along y", Bound::positive},
          {"hz", 0.2, "m", "box half-extent along z", Bound::positive},
          {"gap", 0.02, "m", "gap between columns", Bound::nonnegative},
          {"density", 300.0, "kg/m^3", "boxes' density", Bound::positive},
          {"projectile_radius", 0.15, "m", "projectile (an icosphere) radius", Bound::positive},
          {"projectile_density", 3000.0, "kg/m^3", "projectile density", Bound::positive},
          {"projectile_speed", 12.0, "m/s", "projectile's horizontal speed", Bound::positive},
          {"projectile_distance", 3.0, "m", "how far from the wall (along -x) the projectile starts", Bound::positive},
          {"projectile_height", 0.9, "m", "height at which the projectile's path meets the wall's plane", Bound::positive},
      },
      0.2, 0.6);
  return params;
}

std::unique_ptr<Model> make_dropped_body(const Params& p, const TriangleMesh* mesh) {
  const TriangleMesh shape = mesh ? *mesh : box_mesh(Eigen::Vector3d(p.at("hx"), p.at("hy"), p.at("hz")));
  std::vector<Placed> placed;
  try {
    placed.push_back(place(shape, p.at("density"), Eigen::Vector3d(p.at("x0"), p.at("y0"), p.at("z0")), initial_orientation(p),
                           Eigen::Vector3d(p.at("vx0"), p.at("vy0"), p.at("vz0")), Eigen::Vector3d(p.at("wx0"), p.at("wy0"), p.at("wz0"))));
  } catch (const BadParameter&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw BadParameter("mesh", e.what());
  }
  return std::make_unique<RigidContact>("dropped-body", std::move(placed), p);
}

std::unique_ptr<Model> make_box_stack(const Params& p) {
  // a box's state and shape are a few kilobytes; the count check also refuses what is not whole
  const auto [rows, columns] = particle_grid(p, "rows", "columns", 4096, "boxes");
  const Eigen::Vector3d h(p.at("hx"), p.at("hy"), p.at("hz"));
  const TriangleMesh box = box_mesh(h);
  const Eigen::Quaterniond level = Eigen::Quaterniond::Identity();
  std::vector<Placed> placed;
  for (int c = 0; c < columns; ++c)
    for (int r = 0; r < rows; ++r) {
      const Eigen::Vector3d x(0, (c - (columns - 1) / 2.0) * (2 * h.y() + p.at("gap")), h.z() * (2 * r + 1));
      placed.push_back(place(box, p.at("density"), x, level, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()));
    }
  // thrown from x = -(distance + hx) so that it meets the wall's face x = -hx at the given height: its
  // vertical speed is what gravity takes back over the flight's first half
  const double speed = p.at("projectile_speed"), flight = p.at("projectile_distance") / speed;
  const Eigen::Vector3d start(-h.x() - p.at("projectile_distance"), 0, p.at("projectile_height"));
  placed.push_back(place(sphere_mesh(p.at("projectile_radius"), 1), p.at("projectile_density"), start, level,
                         Eigen::Vector3d(speed, 0, p.at("g") * flight / 2), Eigen::Vector3d::Zero()));
  return std::make_unique<RigidContact>("box-stack", std::move(placed), p);
}

}  // namespace stepwise
