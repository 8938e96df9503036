#include "particles_in_box.hpp"

#include "solvers/capabilities/second_order.hpp"

#include "particle_common.hpp"
#include "plane_collision.hpp"

#include <fmt/format.h>

#include <cmath>

namespace stepwise {
namespace {

constexpr std::array particles_in_box_specs{
    ParamSpec{"count", 100, "", "number of particles N", Bound::positive},
    ParamSpec{"size", 1.0, "m", "edge length L of the cubic box [0, L]^3", Bound::positive},
    ParamSpec{"restitution", 0.8, "", "coefficient of restitution eps of the walls", Bound::unit_interval},
    ParamSpec{"friction", 0.0, "", "Coulomb friction coefficient mu at impacts", Bound::nonnegative},
    ParamSpec{"g", 9.81, "m/s^2", "gravitational acceleration along -z", Bound::nonnegative},
    ParamSpec{"speed", 2.0, "m/s", "initial velocities are uniform in [-speed, speed]^3", Bound::nonnegative},
    ParamSpec{"seed", 1, "", "random seed of the initial state", Bound::nonnegative},
    ParamSpec{"rest_speed", 0.01, "m/s", "a rebound off the floor slower than this ends in resting contact", Bound::positive},
};

// per particle: its six state entries in the integrators' copies (CVODE Adams keeps up to ~25 vectors), and
// six events, each a name and two closures
constexpr double particles_in_box_bytes_per_particle = 32 * 6 * 8 + 6 * 256;

class ParticlesInBox final : public Model, public DenseJacobian, public EventSource {
 public:
  explicit ParticlesInBox(const Params& p)
      : n_(particle_count(p, "count", particles_in_box_bytes_per_particle)), size_(p.at("size")), eps_(p.at("restitution")), mu_(p.at("friction")),
        g_(p.at("g")), speed_(p.at("speed")), seed_(particle_seed(p)), rest_speed_(p.at("rest_speed")) {
    const Eigen::Vector3d o = Eigen::Vector3d::Zero(), l = Eigen::Vector3d::Constant(size_);
    walls_ = {make_plane(o, Eigen::Vector3d::UnitX()), make_plane(l, -Eigen::Vector3d::UnitX()),
              make_plane(o, Eigen::Vector3d::UnitY()), make_plane(l, -Eigen::Vector3d::UnitY()),
              make_plane(o, Eigen::Vector3d::UnitZ()), make_plane(l, -Eigen::Vector3d::UnitZ())};
    for (int i = 0; i < n_; ++i) {
      for (size_t w = 0; w < walls_.size(); ++w) {
        events_.push_back(Event{
            fmt::format("particle {} wall {}", i, w), -1,
            [this, i, w](double, const Eigen::VectorXd& y) { return signed_distance(walls_[w], y.segment<3>(3 * i)); },
            [this, i, w](double, Eigen::VectorXd& y) { return collide(i, walls_[w], y); }});
      }
    }
  }

  std::string_view name() const override { return "particles-in-box"; }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    s.balls = particle_balls(y, n_);
    s.container = Aabb{Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(size_)};
    return s;
  }
  int size() const override { return 6 * n_; }
  bool autonomous() const override { return true; }
  std::vector<std::string> state_names() const override { return particle_state_names(n_); }
  Eigen::VectorXd initial_state() const override {
    std::mt19937_64 rng(seed_);
    Eigen::VectorXd y(6 * n_);
    const double margin = size_ / 20;
    for (int k = 0; k < 3 * n_; ++k) y[k] = margin + (size_ - 2 * margin) * uniform01(rng);
    for (int k = 0; k < 3 * n_; ++k) y[3 * n_ + k] = speed_ * (2 * uniform01(rng) - 1);
    return y;
  }
  const void* capability(const std::type_info& type) const override { return offer(type, second_order_, as_part<DenseJacobian>(*this), as_part<EventSource>(*this)); }
  std::span<const Event> events() const override { return events_; }
  // the shortest return to one wall: a rebound off the floor at rest_speed, up and down
  double event_free_interval() const override { return g_ > 0 ? 2 * rest_speed_ / g_ : std::numeric_limits<double>::infinity(); }

  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    dydt.head(3 * n_) = y.tail(3 * n_);
    dydt.tail(3 * n_).setZero();
    for (int i = 0; i < n_; ++i) {
      // resting contact, set exactly by the event handler: the floor's normal force cancels gravity
      const bool resting = y[3 * i + 2] == 0 && y[3 * n_ + 3 * i + 2] == 0;
      dydt[3 * n_ + 3 * i + 2] = resting ? 0 : -g_;
    }
  }
  void jacobian(double, const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::MatrixXd> dfdy) const override {
    dfdy.setZero();
    dfdy.topRightCorner(3 * n_, 3 * n_).setIdentity();
  }

  std::optional<double> energy(const Eigen::VectorXd& y) const override { return kinetic_and_gravity(y, g_); }

 private:
  // particle i meets `wall`: onto the plane, then the plane response; a slow rebound off the floor rests
  // (exactly on it, z = 0 and vz = 0, which rhs reads as resting contact)
  std::string collide(int i, const Plane& wall, Eigen::VectorXd& y) const {
    const bool floor = wall.normal.z() > 0;
    return plane_contact(wall, y.segment<3>(3 * i), y.segment<3>(3 * n_ + 3 * i), eps_, mu_, floor ? rest_speed_ : 0.0);
  }

  int n_;
  double size_, eps_, mu_, g_, speed_;
  unsigned long seed_;
  double rest_speed_;
  std::array<Plane, 6> walls_;
  std::vector<Event> events_;
  SecondOrderView second_order_{3 * n_};  // y = (x, v)
};

}  // namespace

std::span<const ParamSpec> particles_in_box_params() { return particles_in_box_specs; }

std::unique_ptr<Model> make_particles_in_box(const Params& p) { return std::make_unique<ParticlesInBox>(p); }

}  // namespace stepwise
