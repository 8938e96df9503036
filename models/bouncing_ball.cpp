#include "bouncing_ball.hpp"

#include "solvers/capabilities/second_order.hpp"

#include <cmath>

namespace stepwise {
namespace {

constexpr std::array bouncing_ball_specs{
    ParamSpec{"height", 1.0, "m", "drop height above the ground plane", Bound::positive},
    ParamSpec{"restitution", 0.8, "", "coefficient of restitution eps: rebound speed / impact speed", Bound::unit_interval},
    ParamSpec{"g", 9.81, "m/s^2", "gravitational acceleration", Bound::positive},
    ParamSpec{"rest_speed", 0.01, "m/s", "a rebound slower than this ends in resting contact", Bound::positive},
};

class BouncingBall final : public Model, public DenseJacobian, public EventSource {
 public:
  explicit BouncingBall(const Params& p)
      : h0_(p.at("height")), eps_(p.at("restitution")), g_(p.at("g")), rest_speed_(p.at("rest_speed")) {
    events_.push_back(Event{
        "ground", -1, [](double, const Eigen::VectorXd& y) { return y[0]; },
        [this](double, Eigen::VectorXd& y) -> std::string {
          // still above and rising: the crossing was estimated too early, nothing happens yet
          if (y[0] > 0 && y[1] >= 0) return "";
          // the contact point lies on the plane; the normal velocity reverses, scaled by eps
          const double rebound = -eps_ * y[1];
          y[0] = 0;
          if (rebound < rest_speed_) {
            y[1] = 0;
            return "rest";
          }
          y[1] = rebound;
          return "impact";
        }});
  }

  std::string_view name() const override { return "bouncing-ball"; }
  // the seeds' picture: a sphere over the ground line, in the xy plane with y up. The model's y is the
  // ball's lowest point (its contact point at an impact), so the sphere's centre is one radius above it
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    const double r = 0.08 * h0_;
    s.balls.push_back({Eigen::Vector3d(0, y[0] + r, 0), r, false});
    s.ground = make_plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY());
    s.up = Eigen::Vector3d::UnitY();
    s.planar = true;
    return s;
  }
  int size() const override { return 2; }
  bool autonomous() const override { return true; }
  std::vector<std::string> state_names() const override { return {"y", "vy"}; }
  Eigen::VectorXd initial_state() const override { return Eigen::Vector2d(h0_, 0); }
  const void* capability(const std::type_info& type) const override { return offer(type, second_order_, as_part<DenseJacobian>(*this), as_part<EventSource>(*this)); }
  std::span<const Event> events() const override { return events_; }
  // the shortest flight: a rebound at rest_speed, up and down
  double event_free_interval() const override { return 2 * rest_speed_ / g_; }

  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    // resting contact, set exactly by the event handler: the normal force cancels gravity
    const bool resting = y[0] == 0 && y[1] == 0;
    dydt[0] = y[1];
    dydt[1] = resting ? 0 : -g_;
  }
  void jacobian(double, const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::MatrixXd> dfdy) const override {
    dfdy << 0, 1, 0, 0;
  }

  std::optional<double> energy(const Eigen::VectorXd& y) const override { return 0.5 * y[1] * y[1] + g_ * y[0]; }

  bool has_exact() const override { return true; }
  Eigen::VectorXd exact(double t) const override {
    const double v0 = std::sqrt(2 * g_ * h0_);
    double t_impact = v0 / g_;
    if (t < t_impact) return Eigen::Vector2d(h0_ - 0.5 * g_ * t * t, -g_ * t);
    for (double speed = eps_ * v0;; speed *= eps_) {
      if (speed < rest_speed_) return Eigen::Vector2d(0, 0);
      const double flight = 2 * speed / g_;
      if (t < t_impact + flight) {
        const double tau = t - t_impact;
        return Eigen::Vector2d(speed * tau - 0.5 * g_ * tau * tau, speed - g_ * tau);
      }
      t_impact += flight;
    }
  }

 private:
  double h0_, eps_, g_, rest_speed_;
  std::vector<Event> events_;
  SecondOrderView second_order_{1};  // y = (x, v)
};

}  // namespace

std::span<const ParamSpec> bouncing_ball_params() { return bouncing_ball_specs; }

std::unique_ptr<Model> make_bouncing_ball(const Params& p) { return std::make_unique<BouncingBall>(p); }

std::vector<Bounce> bouncing_ball_impacts(const Params& p, int count) {
  const double h0 = p.at("height"), eps = p.at("restitution"), g = p.at("g"), rest_speed = p.at("rest_speed");
  const double v0 = std::sqrt(2 * g * h0);
  std::vector<Bounce> impacts;
  double t = v0 / g, speed = eps * v0;
  for (int n = 0; n < count; ++n, t += 2 * speed / g, speed *= eps) {
    const bool rest = speed < rest_speed;
    impacts.push_back({t, rest ? 0.0 : speed * speed / (2 * g), rest});
    if (rest) break;
  }
  return impacts;
}

}  // namespace stepwise
