#include "flow_particle.hpp"

#include "solvers/capabilities/inline_rhs.hpp"

#include <gsl/gsl_sf_expint.h>

#include <cmath>
#include <numbers>

namespace stepwise {
namespace {

constexpr std::array params_2d{
    ParamSpec{"x0", 1.0, "m", "initial x", Bound::finite},
    ParamSpec{"y0", 1.0, "m", "initial y", Bound::finite},
};
constexpr std::array params_3d{
    ParamSpec{"x0", 1.0, "m", "initial x", Bound::finite},
    ParamSpec{"y0", 1.0, "m", "initial y", Bound::finite},
    ParamSpec{"z0", 1.0, "m", "initial z", Bound::finite},
};

class FlowParticle final : public Model, public DenseJacobian {
 public:
  explicit FlowParticle(const Params& p) : x0_(p.at("x0")), y0_(p.at("y0")) {}
  std::string_view name() const override { return "flow-particle"; }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    s.balls.push_back({Eigen::Vector3d(y[0], y[1], 0), 0, true});
    s.up = Eigen::Vector3d::UnitY();
    s.planar = true;
    return s;
  }
  int size() const override { return 2; }
  bool autonomous() const override { return true; }
  std::vector<std::string> state_names() const override { return {"x", "y"}; }
  Eigen::VectorXd initial_state() const override { return Eigen::Vector2d(x0_, y0_); }

  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& p, Eigen::Ref<Eigen::VectorXd> dpdt) const override {
    std::get<FlowParticleRhs>(inline_rhs_.f)(t, p.data(), dpdt.data());
  }
  const void* capability(const std::type_info& type) const override { return offer(type, inline_rhs_, as_part<DenseJacobian>(*this)); }
  void jacobian(double, const Eigen::Ref<const Eigen::VectorXd>& p, Eigen::Ref<Eigen::MatrixXd> dfdp) const override {
    dfdp << 1, 0, 0, std::cos(p[1]);
  }

  bool has_exact() const override { return true; }
  Eigen::VectorXd exact(double t) const override {
    // sin y has zeros at multiples of pi: y stays in the band (2 pi n - pi, 2 pi n + pi) it starts in
    const double turns = std::round(y0_ / (2 * std::numbers::pi));
    const double y_reduced = y0_ - 2 * std::numbers::pi * turns;
    const double y = std::abs(y_reduced) == std::numbers::pi ? y_reduced : 2 * std::atan(std::tan(y_reduced / 2) * std::exp(t));
    return Eigen::Vector2d(x0_ * std::exp(t), y + 2 * std::numbers::pi * turns);
  }

 private:
  double x0_, y0_;
  InlineRhs inline_rhs_{FlowParticleRhs{}};  // f, for the steppers that call it inline
};

class FlowParticle3d final : public Model, public DenseJacobian {
 public:
  explicit FlowParticle3d(const Params& p) : x0_(p.at("x0")), y0_(p.at("y0")), z0_(p.at("z0")) {}
  std::string_view name() const override { return "flow-particle-3d"; }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    s.balls.push_back({y.head<3>(), 0, true});
    return s;
  }
  int size() const override { return 3; }
  bool autonomous() const override { return true; }
  std::vector<std::string> state_names() const override { return {"x", "y", "z"}; }
  Eigen::VectorXd initial_state() const override { return Eigen::Vector3d(x0_, y0_, z0_); }

  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& p, Eigen::Ref<Eigen::VectorXd> dpdt) const override {
    dpdt[0] = p[0];
    dpdt[1] = p[1];
    dpdt[2] = std::sin(p[0]);
  }
  const void* capability(const std::type_info& type) const override { return offer(type, as_part<DenseJacobian>(*this)); }
  void jacobian(double, const Eigen::Ref<const Eigen::VectorXd>& p, Eigen::Ref<Eigen::MatrixXd> dfdp) const override {
    dfdp << 1, 0, 0, 0, 1, 0, std::cos(p[0]), 0, 0;
  }

  bool has_exact() const override { return true; }
  Eigen::VectorXd exact(double t) const override {
    const double x = x0_ * std::exp(t);
    return Eigen::Vector3d(x, y0_ * std::exp(t), z0_ + gsl_sf_Si(x) - gsl_sf_Si(x0_));
  }

 private:
  double x0_, y0_, z0_;
};

}  // namespace

std::span<const ParamSpec> flow_particle_params() { return params_2d; }
std::span<const ParamSpec> flow_particle_3d_params() { return params_3d; }
std::unique_ptr<Model> make_flow_particle(const Params& p) { return std::make_unique<FlowParticle>(p); }
std::unique_ptr<Model> make_flow_particle_3d(const Params& p) { return std::make_unique<FlowParticle3d>(p); }

}  // namespace stepwise
