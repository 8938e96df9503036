#include "pendulum.hpp"

#include "solvers/capabilities/inline_rhs.hpp"
#include "solvers/capabilities/second_order.hpp"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_sf_ellint.h>
#include <gsl/gsl_sf_elljac.h>

#include <cmath>
#include <limits>
#include <numbers>

namespace stepwise {
namespace {

// GSL's default error handler aborts the process on a domain error: report through return values instead
const bool gsl_abort_handler_off = (gsl_set_error_handler_off(), true);

constexpr std::array pendulum_specs{
    ParamSpec{"theta0", 1.0, "rad", "initial angle from the downward vertical", Bound::finite},
    ParamSpec{"omega0", 0.0, "rad/s", "initial angular velocity", Bound::finite},
    ParamSpec{"g", 9.81, "m/s^2", "gravitational acceleration", Bound::positive},
    ParamSpec{"length", 1.0, "m", "pendulum length", Bound::positive},
    ParamSpec{"mass", 1.0, "kg", "bob mass (scales the energy only)", Bound::positive},
};

class Pendulum final : public Model, public DenseJacobian {
 public:
  Pendulum(const Params& p, bool small_angle)
      : theta0_(p.at("theta0")), omega0_(p.at("omega0")), g_(p.at("g")), length_(p.at("length")),
        mass_(p.at("mass")), w_(std::sqrt(g_ / length_)), small_angle_(small_angle) {
    const double s = std::sin(theta0_ / 2);
    k_ = std::sqrt(s * s + omega0_ * omega0_ / (4 * w_ * w_));
    if (!small_angle_ && k_ > 0 && k_ < 1) {
      quarter_ = gsl_sf_ellint_Kcomp(k_, GSL_PREC_DOUBLE);
      u0_ = gsl_sf_ellint_F(std::atan2(s / k_, omega0_ / (2 * k_ * w_)), k_, GSL_PREC_DOUBLE);
    }
  }

  std::string_view name() const override { return small_angle_ ? "pendulum-small-angle" : "pendulum"; }
  // the pivot at the origin, the bob at angle theta from straight down, in the xy plane with y up
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    const Eigen::Vector3d bob(length_ * std::sin(y[0]), -length_ * std::cos(y[0]), 0);
    s.lines.push_back({Eigen::Vector3d::Zero(), bob});
    s.balls.push_back({bob, 0.08 * length_, true});
    s.up = Eigen::Vector3d::UnitY();
    s.planar = true;
    return s;
  }
  int size() const override { return 2; }
  bool autonomous() const override { return true; }
  std::vector<std::string> state_names() const override { return {"theta", "omega"}; }
  Eigen::VectorXd initial_state() const override { return Eigen::Vector2d(theta0_, omega0_); }
  const void* capability(const std::type_info& type) const override { return offer(type, second_order_, inline_rhs_, as_part<DenseJacobian>(*this)); }

  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    std::get<PendulumRhs>(inline_rhs_.f)(t, y.data(), dydt.data());
  }

  void jacobian(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::MatrixXd> dfdy) const override {
    dfdy << 0, 1, -w_ * w_ * (small_angle_ ? 1.0 : std::cos(y[0])), 0;
  }

  std::optional<double> energy(const Eigen::VectorXd& y) const override {
    const double kinetic = 0.5 * mass_ * length_ * length_ * y[1] * y[1];
    const double potential = small_angle_ ? 0.5 * mass_ * g_ * length_ * y[0] * y[0]
                                          : mass_ * g_ * length_ * (1 - std::cos(y[0]));
    return kinetic + potential;
  }

  bool has_exact() const override { return small_angle_ || k_ < 1; }

  Eigen::VectorXd exact(double t) const override {
    if (small_angle_) {
      const double c = std::cos(w_ * t), s = std::sin(w_ * t);
      return Eigen::Vector2d(theta0_ * c + omega0_ / w_ * s, -theta0_ * w_ * s + omega0_ * c);
    }
    if (k_ == 0) return Eigen::Vector2d(0, 0);
    if (k_ >= 1) return Model::exact(t);
    // reduce u modulo the period 4K of sn and cn so long runs keep their digits
    const double u = std::fmod(w_ * t + u0_, 4 * quarter_);
    double sn = 0, cn = 0, dn = 0;
    gsl_sf_elljac_e(u, k_ * k_, &sn, &cn, &dn);
    return Eigen::Vector2d(2 * std::asin(k_ * sn), 2 * k_ * w_ * cn);
  }

 private:
  double theta0_, omega0_, g_, length_, mass_;
  double w_;           // small-angle angular frequency sqrt(g/L) [rad/s]
  bool small_angle_;
  double k_ = 0;       // elliptic modulus: sin of half the turning angle
  double quarter_ = 0; // K(k): a quarter period in units of 1/w
  double u0_ = 0;      // phase of the initial state in units of 1/w
  SecondOrderView second_order_{1};  // y = (x, v)
  InlineRhs inline_rhs_{PendulumRhs{w_ * w_, small_angle_}};  // f, for the steppers that call it inline
};

}  // namespace

std::span<const ParamSpec> pendulum_params() { return pendulum_specs; }

std::unique_ptr<Model> make_pendulum(const Params& p, bool small_angle) { return std::make_unique<Pendulum>(p, small_angle); }

double pendulum_period(double theta0, double g, double length) {
  (void)gsl_abort_handler_off;
  if (std::abs(theta0) >= std::numbers::pi) return std::numeric_limits<double>::infinity();
  return 4 * gsl_sf_ellint_Kcomp(std::sin(std::abs(theta0) / 2), GSL_PREC_DOUBLE) / std::sqrt(g / length);
}

}  // namespace stepwise
