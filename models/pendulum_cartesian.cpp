#include "pendulum_cartesian.hpp"

#include "pendulum.hpp"
#include "springs.hpp"
#include "solvers/capabilities/distance_constraints.hpp"
#include "solvers/capabilities/second_order.hpp"

#include <array>
#include <cmath>

namespace stepwise {
namespace {

constexpr std::array pendulum_cartesian_specs{
    ParamSpec{"theta0", 1.0, "rad", "initial angle from the downward vertical", Bound::finite},
    ParamSpec{"omega0", 0.0, "rad/s", "initial angular velocity", Bound::finite},
    ParamSpec{"g", 9.81, "m/s^2", "gravitational acceleration", Bound::positive},
    ParamSpec{"length", 1.0, "m", "pendulum length (the rod's rest length)", Bound::positive},
    ParamSpec{"mass", 1.0, "kg", "bob mass", Bound::positive},
    ParamSpec{"compliance", 0.0, "m/N", "the rod's compliance alpha = 1/stiffness (0: rigid)", Bound::nonnegative},
    ParamSpec{"baumgarte", 0, "", "Baumgarte stabilisation of the rigid rod's equations (1: on, --constraint baumgarte)", Bound::flag},
};

class PendulumCartesian final : public Model {
 public:
  explicit PendulumCartesian(const Params& p)
      : theta0_(p.at("theta0")), omega0_(p.at("omega0")), g_(p.at("g")), length_(p.at("length")), mass_(p.at("mass")),
        compliance_(p.at("compliance")), baumgarte_(p.at("baumgarte") == 1 ? baumgarte_rate(g_, length_) : 0.0),
        reduced_(make_pendulum(p, false)) {
    constraints_.dimension = 2;
    constraints_.inverse_mass = {1 / mass_};
    constraints_.constraints = {DistanceConstraint{0, -1, Eigen::Vector3d::Zero(), length_, compliance_}};
    constraints_.external = [g = g_](double, const double*, const double*, double* a) {
      a[0] = 0;
      a[1] = -g;
    };
    // a compliant rod is a spring of stiffness 1 / alpha from the pivot: a mass-spring system in the plane
    if (compliance_ > 0) rod_ = std::make_unique<SpringNetwork>(std::vector{mass_}, std::vector{Spring{-1, 0, length_, 1 / compliance_}}, 2);
  }
  PendulumCartesian(const PendulumCartesian&) = delete;  // its rod's view holds the rod
  PendulumCartesian& operator=(const PendulumCartesian&) = delete;
  std::string_view name() const override { return "pendulum-cartesian"; }
  int size() const override { return 4; }
  bool autonomous() const override { return true; }
  std::vector<std::string> state_names() const override { return {"x", "y", "vx", "vy"}; }
  Eigen::VectorXd initial_state() const override { return from_angle(theta0_, omega0_); }
  const void* capability(const std::type_info& type) const override {
    if (rod_)
      if (const void* found = offer(type, rod_->view(), rod_->network())) return found;
    return offer(type, second_order_, constraints_);
  }

  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    const Eigen::Vector2d x = y.head<2>(), v = y.tail<2>(), g(0, -g_);
    Eigen::Vector2d a;
    if (rod_) {
      a = g;
      Eigen::Vector2d pull = Eigen::Vector2d::Zero();
      add_spring_forces(rod_->view().springs, x.data(), v.data(), pull.data(), 2);
      a += pull / mass_;
    } else {
      // g = (|x|^2 - L^2) / 2: g'' = |v|^2 + x . a held at -2 w g' - w^2 g (0 without Baumgarte)
      const double drift = 0.5 * (x.squaredNorm() - length_ * length_), rate = x.dot(v);
      a = g - (v.squaredNorm() + x.dot(g) + 2 * baumgarte_ * rate + baumgarte_ * baumgarte_ * drift) / x.squaredNorm() * x;
    }
    dydt << v, a;
  }
  std::optional<double> energy(const Eigen::VectorXd& y) const override {
    return 0.5 * mass_ * y.tail<2>().squaredNorm() + mass_ * g_ * y[1] + (rod_ ? rod_->view().potential(y.head<2>()) : 0.0);
  }
  bool has_exact() const override { return compliance_ == 0 && reduced_->has_exact(); }
  Eigen::VectorXd exact(double t) const override {
    if (!has_exact()) return Model::exact(t);
    const Eigen::VectorXd angle = reduced_->exact(t);
    return from_angle(angle[0], angle[1]);
  }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    const Eigen::Vector3d bob(y[0], y[1], 0);
    s.lines.push_back({Eigen::Vector3d::Zero(), bob});
    s.balls.push_back({bob, 0.08 * length_, true});
    s.up = Eigen::Vector3d::UnitY();
    s.planar = true;
    return s;
  }

 private:
  Eigen::VectorXd from_angle(double theta, double omega) const {
    Eigen::VectorXd y(4);
    y << length_ * std::sin(theta), -length_ * std::cos(theta), length_ * omega * std::cos(theta), length_ * omega * std::sin(theta);
    return y;
  }
  double theta0_, omega0_, g_, length_, mass_, compliance_;
  double baumgarte_;  // w (1/s), 0: off
  std::unique_ptr<Model> reduced_;  // the pendulum in its angle: the exact solution
  std::unique_ptr<SpringNetwork> rod_;  // the compliant rod (compliance > 0) as a spring from the pivot
  SecondOrderView second_order_{2};
  DistanceConstraints constraints_;
};

}  // namespace

std::span<const ParamSpec> pendulum_cartesian_params() { return pendulum_cartesian_specs; }

std::unique_ptr<Model> make_pendulum_cartesian(const Params& p) { return std::make_unique<PendulumCartesian>(p); }

}  // namespace stepwise
