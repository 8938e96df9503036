#include "projectile.hpp"

#include "solvers/capabilities/inline_rhs.hpp"
#include "solvers/capabilities/second_order.hpp"

#include <cmath>

namespace stepwise {
namespace {

constexpr std::array projectile_specs{
    ParamSpec{"x0", 0.0, "m", "initial x", Bound::finite},
    ParamSpec{"y0", 0.0, "m", "initial height", Bound::finite},
    ParamSpec{"vx0", 10.0, "m/s", "initial horizontal velocity", Bound::finite},
    ParamSpec{"vy0", 10.0, "m/s", "initial vertical velocity", Bound::finite},
    ParamSpec{"g", 9.81, "m/s^2", "gravitational acceleration", Bound::nonnegative},
    ParamSpec{"drag", 0.0, "1/s", "linear drag coefficient per unit mass", Bound::nonnegative},
    ParamSpec{"mass", 1.0, "kg", "particle mass (scales the energy only)", Bound::positive},
};

class Projectile final : public Model, public DenseJacobian {
 public:
  explicit Projectile(const Params& p)
      : x0_(p.at("x0")), y0_(p.at("y0")), vx0_(p.at("vx0")), vy0_(p.at("vy0")), g_(p.at("g")), k_(p.at("drag")),
        mass_(p.at("mass")) {}
  std::string_view name() const override { return "projectile"; }
  // in the xy plane, y up, over the ground y = 0
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    s.balls.push_back({Eigen::Vector3d(y[0], y[1], 0), 0, true});
    s.ground = make_plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY());
    s.up = Eigen::Vector3d::UnitY();
    s.planar = true;
    return s;
  }
  int size() const override { return 4; }
  bool autonomous() const override { return true; }
  std::vector<std::string> state_names() const override { return {"x", "y", "vx", "vy"}; }
  Eigen::VectorXd initial_state() const override { return Eigen::Vector4d(x0_, y0_, vx0_, vy0_); }
  const void* capability(const std::type_info& type) const override { return offer(type, second_order_, inline_rhs_, as_part<DenseJacobian>(*this)); }

  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& s, Eigen::Ref<Eigen::VectorXd> dsdt) const override {
    std::get<ProjectileRhs>(inline_rhs_.f)(t, s.data(), dsdt.data());
  }
  void jacobian(double, const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::MatrixXd> dfds) const override {
    dfds << 0, 0, 1, 0,
            0, 0, 0, 1,
            0, 0, -k_, 0,
            0, 0, 0, -k_;
  }

  std::optional<double> energy(const Eigen::VectorXd& s) const override {
    return 0.5 * mass_ * (s[2] * s[2] + s[3] * s[3]) + mass_ * g_ * s[1];
  }

  bool has_exact() const override { return true; }
  Eigen::VectorXd exact(double t) const override {
    // E(t) = (1 - e^{-kt})/k and (t - E(t))/k = t^2 (e^{-x} - 1 + x)/x^2 with x = kt; the latter by its
    // series sum_{n>=2} (-x)^(n-2)/n! where x is small, since the closed form cancels there
    const double x = k_ * t;
    const double e = x == 0 ? t : -std::expm1(-x) / k_;
    double rest = 0;
    if (x < 0.5) {
      double term = 0.5;  // (-x)^(n-2)/n! at n = 2
      for (int n = 2; n < 30; ++n) {
        rest += term;
        term *= -x / (n + 1);
      }
      rest *= t * t;
    } else {
      rest = (t - e) / k_;
    }
    const double decay = std::exp(-x);
    return Eigen::Vector4d(x0_ + vx0_ * e, y0_ + vy0_ * e - g_ * rest, vx0_ * decay, vy0_ * decay - g_ * e);
  }

 private:
  double x0_, y0_, vx0_, vy0_, g_, k_, mass_;
  SecondOrderView second_order_{2};  // y = (x, v)
  InlineRhs inline_rhs_{ProjectileRhs{g_, k_}};  // f, for the steppers that call it inline
};

}  // namespace

std::span<const ParamSpec> projectile_params() { return projectile_specs; }
std::unique_ptr<Model> make_projectile(const Params& p) { return std::make_unique<Projectile>(p); }

}  // namespace stepwise
