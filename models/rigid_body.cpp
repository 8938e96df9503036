#include "rigid_body.hpp"

#include "solvers/capabilities/free_rigid_body.hpp"

#include "mass_properties.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_sf_ellint.h>
#include <gsl/gsl_sf_elljac.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace stepwise {
namespace {

const ParamSpec rigid_body_specs[] = {
    {"mass", 1.0, "kg", "mass", Bound::positive},
    {"I1", 1.0, "kg m^2", "principal moment about the body x axis", Bound::positive},
    {"I2", 2.0, "kg m^2", "principal moment about the body y axis", Bound::positive},
    {"I3", 3.0, "kg m^2", "principal moment about the body z axis", Bound::positive},
    {"x0", 0.0, "m", "initial centre of mass x"},
    {"y0", 0.0, "m", "initial centre of mass y"},
    {"z0", 0.0, "m", "initial centre of mass z (height)"},
    {"vx0", 0.0, "m/s", "initial velocity x"},
    {"vy0", 0.0, "m/s", "initial velocity y"},
    {"vz0", 0.0, "m/s", "initial velocity z"},
    {"qw0", 1.0, "", "initial orientation quaternion, scalar part (normalised; not all four zero)"},
    {"qx0", 0.0, "", "initial orientation quaternion, x"},
    {"qy0", 0.0, "", "initial orientation quaternion, y"},
    {"qz0", 0.0, "", "initial orientation quaternion, z"},
    {"wx0", 0.01, "rad/s", "initial angular velocity about the body x axis"},
    {"wy0", 1.0, "rad/s", "initial angular velocity about the body y axis"},
    {"wz0", 0.0, "rad/s", "initial angular velocity about the body z axis"},
    {"g", 0.0, "m/s^2", "gravitational acceleration, along -z", Bound::nonnegative},
    {"drag", 0.0, "1/s", "linear drag per unit mass", Bound::nonnegative},
    {"angular_drag", 0.0, "1/s", "angular damping: torque -angular_drag I w", Bound::nonnegative},
    {"fx", 0.0, "N", "constant applied force, world x"},
    {"fy", 0.0, "N", "constant applied force, world y"},
    {"fz", 0.0, "N", "constant applied force, world z"},
    {"px", 0.0, "m", "body point the force acts at, body x (torque r x f)"},
    {"py", 0.0, "m", "body point the force acts at, body y"},
    {"pz", 0.0, "m", "body point the force acts at, body z"},
    {"density", 1000.0, "kg/m^3", "with a [mesh]: its uniform density, from which mass and I1-I3 follow (they may not be given then)", Bound::positive},
};

// half-extents of the uniform box of mass m with principal moments I: I1 = m (b^2 + c^2) / 3 and its
// cyclic twins give a^2 = 3 (I2 + I3 - I1) / (2 m); moments at the triangle inequality's edge, a flat box
Eigen::Vector3d equivalent_box(double m, const Eigen::Vector3d& I) {
  Eigen::Vector3d h;
  for (int k = 0; k < 3; ++k) h[k] = std::sqrt(std::max(0.0, 3 * (I.sum() - 2 * I[k]) / (2 * m)));
  return h.cwiseMax(1e-2 * h.maxCoeff());
}

class RigidBody final : public Model, public Projection {
 public:
  // shape: the body's surface in its principal frame; empty: the box with these principal moments
  explicit RigidBody(const Params& p, std::optional<TriangleMesh> shape = std::nullopt)
      : mass_(p.at("mass")), inertia_(p.at("I1"), p.at("I2"), p.at("I3")), gravity_(0, 0, -p.at("g")), drag_(p.at("drag")),
        angular_drag_(p.at("angular_drag")), force_(p.at("fx"), p.at("fy"), p.at("fz")), point_(p.at("px"), p.at("py"), p.at("pz")) {
    if (const int k = moment_beyond_the_others(inertia_); k >= 0)
      throw BadParameter(fmt::format("I{}", k + 1), fmt::format("principal moment I{} = {:g} exceeds the sum of the other two ({:g}): no body has "
                                                                "these moments", k + 1, inertia_[k], inertia_.sum() - inertia_[k]));
    const Eigen::Quaterniond q = initial_orientation(p);
    y0_.resize(13);
    y0_ << p.at("x0"), p.at("y0"), p.at("z0"), p.at("vx0"), p.at("vy0"), p.at("vz0"), q.w(), q.x(), q.y(), q.z(), p.at("wx0"), p.at("wy0"),
        p.at("wz0");
    shape_ = shape ? std::move(*shape) : box_mesh(equivalent_box(mass_, inertia_));
    if (drag_ == 0 && angular_drag_ == 0 && point_.cross(force_).isZero()) free_ = RigidBodyView{inertia_, gravity_ + force_ / mass_};
  }

  std::string_view name() const override { return "rigid-body"; }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    const Eigen::Quaterniond q(y[6], y[7], y[8], y[9]);
    s.bodies.push_back({&shape_, q.normalized().toRotationMatrix(), y.head<3>()});
    return s;
  }
  int size() const override { return 13; }
  bool autonomous() const override { return true; }
  std::vector<std::string> state_names() const override { return rigid_body_state_names(1); }
  Eigen::VectorXd initial_state() const override { return y0_; }

  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    const Eigen::Vector3d v = y.segment<3>(3);
    dydt.segment<3>(0) = v;
    dydt.segment<3>(3) = gravity_ - drag_ * v + force_ / mass_;
    free_rotation_rates(inertia_, y, dydt);
    // the torques beyond Euler's: angular damping, and the force at its point
    Eigen::Vector3d torque = -angular_drag_ * inertia_.cwiseProduct(y.segment<3>(10));
    if (!point_.isZero()) torque += point_.cross(Eigen::Quaterniond(y[6], y[7], y[8], y[9]).normalized().conjugate() * force_);
    dydt.segment<3>(10) += torque.cwiseQuotient(inertia_);
  }

  void project(Eigen::Ref<Eigen::VectorXd> y) const override { y.segment<4>(6).normalize(); }

  const void* capability(const std::type_info& type) const override {
    if (type == typeid(Projection)) return &as_part<Projection>(*this);
    return free_ ? offer(type, *free_) : nullptr;
  }

  std::optional<double> energy(const Eigen::VectorXd& y) const override {
    return body_kinetic_energy(mass_, inertia_, y.segment<3>(3), y.segment<3>(10)) - mass_ * gravity_.dot(y.segment<3>(0));
  }

  std::vector<std::string> summary_names() const override {
    auto names = state_names();
    names.insert(names.end(), {"energy", "Lx", "Ly", "Lz"});
    return names;
  }
  Eigen::VectorXd summary(const Eigen::VectorXd& y) const override {
    Eigen::VectorXd s(17);
    s << y, *energy(y), body_angular_momentum(inertia_, y);
    return s;
  }

 private:
  double mass_;
  Eigen::Vector3d inertia_, gravity_;
  double drag_, angular_drag_;
  Eigen::Vector3d force_, point_;
  Eigen::VectorXd y0_;
  TriangleMesh shape_;  // as drawn, body frame
  std::optional<RigidBodyView> free_;  // torque-free: no drag and the force through the centre of mass
};

// F(phi, k) for phi in [-pi, pi], through F(pi - phi) = 2K - F(phi) and oddness
double elliptic_f(double phi, double k, double K) {
  const double magnitude = std::abs(phi);
  const double f = magnitude <= std::numbers::pi / 2 ? gsl_sf_ellint_F(magnitude, k, GSL_PREC_DOUBLE)
                                                     : 2 * K - gsl_sf_ellint_F(std::numbers::pi - magnitude, k, GSL_PREC_DOUBLE);
  return std::copysign(f, phi);
}

}  // namespace

std::span<const ParamSpec> rigid_body_params() { return rigid_body_specs; }

Eigen::Quaterniond initial_orientation(const Params& p) {
  const Eigen::Vector4d q(p.at("qw0"), p.at("qx0"), p.at("qy0"), p.at("qz0"));
  if (!(q.norm() > 0)) throw BadParameter("qw0", "initial orientation quaternion (qw0, qx0, qy0, qz0) is zero");
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
}

std::vector<std::string> rigid_body_state_names(int bodies) {
  static const char* const names[] = {"x", "y", "z", "vx", "vy", "vz", "qw", "qx", "qy", "qz", "wx", "wy", "wz"};
  std::vector<std::string> out;
  for (int b = 0; b < bodies; ++b)
    for (const char* n : names) out.push_back(bodies == 1 ? std::string(n) : fmt::format("{}[{}]", n, b));
  return out;
}

Eigen::Vector3d body_angular_momentum(const Eigen::Vector3d& inertia, const Eigen::Ref<const Eigen::VectorXd>& y) {
  return Eigen::Quaterniond(y[6], y[7], y[8], y[9]).normalized() * inertia.cwiseProduct(y.segment<3>(10));
}

void free_rotation_rates(const Eigen::Vector3d& inertia, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) {
  const Eigen::Vector3d w = y.segment<3>(10);
  const Eigen::Quaterniond dq = Eigen::Quaterniond(y[6], y[7], y[8], y[9]) * Eigen::Quaterniond(0, w.x(), w.y(), w.z());
  dydt.segment<4>(6) << dq.w() / 2, dq.x() / 2, dq.y() / 2, dq.z() / 2;
  dydt.segment<3>(10) = inertia.cwiseProduct(w).cross(w).cwiseQuotient(inertia);
}
std::unique_ptr<Model> make_rigid_body(const Params& p) { return std::make_unique<RigidBody>(p); }

std::unique_ptr<Model> make_rigid_body(const Params& p, const TriangleMesh& mesh) {
  for (const ParamSpec& spec : rigid_body_specs)
    if ((spec.key == "mass" || spec.key.starts_with("I")) && p.at(std::string(spec.key)) != spec.default_value)
      throw BadParameter(std::string(spec.key), fmt::format("parameter '{}' follows from the [mesh] and its density: give one or the other", spec.key));
  Params with = p;
  PrincipalFrame frame;
  MassProperties props;
  try {
    props = mass_properties(mesh, p.at("density"));
    frame = principal_frame(props.inertia);
    with["mass"] = props.mass;
  } catch (const std::invalid_argument& e) {
    throw BadParameter("mesh", e.what());
  }
  for (int k = 0; k < 3; ++k) with[fmt::format("I{}", k + 1)] = frame.moments[k];
  // the orientation given is the mesh's; the body's axes are its principal axes within it
  const Eigen::Quaterniond body = initial_orientation(p) * Eigen::Quaterniond(frame.axes);
  with["qw0"] = body.w();
  with["qx0"] = body.x();
  with["qy0"] = body.y();
  with["qz0"] = body.z();
  // the mesh in the principal frame: p_body = A^T (p_mesh - c)
  TriangleMesh shape = mesh;
  shape.vertices = (mesh.vertices.rowwise() - props.center.transpose()) * frame.axes;
  return std::make_unique<RigidBody>(with, std::move(shape));
}

TorqueFreeRotation::TorqueFreeRotation(const Eigen::Vector3d& I, const Eigen::Vector3d& w0) : w0_(w0) {
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int i, int j) { return I[i] < I[j]; });
  const Eigen::Vector3d momentum = I.cwiseProduct(w0);
  const double two_e = w0.dot(momentum), m2 = momentum.squaredNorm();
  // a body with equal moments, or spinning about a principal axis: w stays w0
  if (I[order[2]] - I[order[0]] <= 1e-14 * I[order[2]] || momentum.cross(w0).norm() <= 1e-15 * momentum.norm() * w0.norm()) {
    steady_ = true;
    period_ = std::numeric_limits<double>::infinity();
    return;
  }
  if (m2 > two_e * I[order[1]]) std::tie(a_, b_, c_) = std::tuple{order[0], order[1], order[2]};
  else std::tie(a_, b_, c_) = std::tuple{order[2], order[1], order[0]};
  const double Ia = I[a_], Ib = I[b_], Ic = I[c_];
  const double Aa = std::sqrt((two_e * Ic - m2) / (Ia * (Ic - Ia))), Ab = std::sqrt((two_e * Ic - m2) / (Ib * (Ic - Ib))),
               Ac = std::sqrt((m2 - two_e * Ia) / (Ic * (Ic - Ia)));
  s_ = std::sqrt((Ic - Ib) * (m2 - two_e * Ia) / (Ia * Ib * Ic));
  m_ = (Ib - Ia) * (two_e * Ic - m2) / ((Ic - Ib) * (m2 - two_e * Ia));
  if (!(m_ < 1)) throw std::domain_error("torque-free rotation on the separatrix (k = 1): not periodic");
  const double k = std::sqrt(m_);
  quarter_ = gsl_sf_ellint_Kcomp(k, GSL_PREC_DOUBLE);
  period_ = 4 * quarter_ / s_;
  // signs: w_c keeps its sign (dn > 0); of the pairs (sign of w_b, direction of time) the one whose
  // derivative at t = 0 is Euler's
  const double sc = w0[c_] < 0 ? -1 : 1;
  const Eigen::Vector3d euler = momentum.cross(w0).cwiseQuotient(I);
  double best = std::numeric_limits<double>::infinity();
  for (const double sb : {1.0, -1.0})
    for (const double direction : {1.0, -1.0}) {
      const double sn = w0[b_] / (sb * Ab), cn = w0[a_] / Aa, dn = w0[c_] / (sc * Ac);
      // d/dtau: sn' = cn dn, cn' = -sn dn, dn' = -k^2 sn cn
      const double rate = direction * s_;
      const double mismatch = std::hypot(Aa * (-sn * dn) * rate - euler[a_], sb * Ab * (cn * dn) * rate - euler[b_]) +
                              std::abs(sc * Ac * (-m_ * sn * cn) * rate - euler[c_]);
      if (mismatch < best) {
        best = mismatch;
        amp_[0] = Aa;
        amp_[1] = sb * Ab;
        amp_[2] = sc * Ac;
        tau0_ = elliptic_f(std::atan2(sn, cn), k, quarter_);
        s_ = std::abs(s_) * direction;
      }
    }
}

Eigen::Vector3d TorqueFreeRotation::omega(double t) const {
  if (steady_) return w0_;
  // Jacobi's functions have period 4K in tau: reduce first, so a long run keeps its accuracy
  const double tau = std::remainder(tau0_ + s_ * t, 4 * quarter_);
  double sn = 0, cn = 0, dn = 0;
  gsl_sf_elljac_e(tau, m_, &sn, &cn, &dn);
  Eigen::Vector3d w;
  w[a_] = amp_[0] * cn;
  w[b_] = amp_[1] * sn;
  w[c_] = amp_[2] * dn;
  return w;
}

}  // namespace stepwise
