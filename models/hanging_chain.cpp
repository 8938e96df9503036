#include "hanging_chain.hpp"

#include "solvers/capabilities/second_order.hpp"
#include "solvers/capabilities/mass_spring.hpp"

#include "particle_common.hpp"
#include "springs.hpp"

#include <fmt/format.h>

namespace stepwise {

namespace {

const ParamSpec hanging_chain_specs[] = {
    {"nodes", 10, "", "free masses below the pin", Bound::positive},
    {"mass", 0.1, "kg", "mass of each node", Bound::positive},
    {"stiffness", 100.0, "N/m", "spring constant c", Bound::positive},
    {"rest_length", 0.1, "m", "rest length l of each spring", Bound::positive},
    {"damping", 2.0, "N s/m", "Voigt damping gamma along each spring", Bound::nonnegative},
    {"drag", 0.0, "1/s", "linear drag of each node per unit mass", Bound::nonnegative},
    {"g", 9.81, "m/s^2", "gravitational acceleration, along -y", Bound::nonnegative},
};

// node k hangs from node k - 1, node 0 from the pin at the origin
std::vector<Spring> chain_springs(int nodes, const Params& p) {
  std::vector<Spring> springs;
  for (int k = 0; k < nodes; ++k) springs.push_back(Spring{k - 1, k, p.at("rest_length"), p.at("stiffness"), p.at("damping")});
  return springs;
}

// the nodes, checked against the memory rule (a node's state, springs, pattern and a dense-free Newton system: ~1 KiB)
int node_count(const Params& p) { return particle_count(p, "nodes", 1024, "nodes"); }

class HangingChain final : public Model, public SparseJacobian {
 public:
  explicit HangingChain(const Params& p)
      : n_(node_count(p)),
        mass_(p.at("mass")),
        drag_(p.at("drag")),
        g_(p.at("g")),
        springs_(std::vector<double>(n_, mass_), chain_springs(n_, p), 3, drag_) {
    y0_ = Eigen::VectorXd::Zero(6 * n_);
    for (int k = 0; k < n_; ++k) y0_[3 * k + 1] = -(k + 1) * p.at("rest_length");
    second_order_.positions = 3 * n_;
    second_order_.acceleration = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> a) { acceleration(t, y, a); };
  }
  HangingChain(const HangingChain&) = delete;  // its capabilities hold `this`
  HangingChain& operator=(const HangingChain&) = delete;

  std::string_view name() const override { return "hanging-chain"; }
  // the pin at the origin, then the nodes, y up
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    s.balls = particle_balls(y, n_);
    s.lines.emplace_back(1, Eigen::Vector3d::Zero());
    for (const auto& ball : s.balls) s.lines.back().push_back(ball.center);
    s.up = Eigen::Vector3d::UnitY();
    return s;
  }
  int size() const override { return 6 * n_; }
  bool autonomous() const override { return true; }
  const void* capability(const std::type_info& type) const override { return offer(type, second_order_, springs_.view(), springs_.network(), as_part<SparseJacobian>(*this)); }
  std::vector<std::string> state_names() const override {
    std::vector<std::string> names;
    for (const char* q : {"", "v"})
      for (int k = 0; k < n_; ++k)
        for (const char* axis : {"x", "y", "z"}) names.push_back(fmt::format("{}{}[{}]", q, axis, k));
    return names;
  }
  Eigen::VectorXd initial_state() const override { return y0_; }

  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    dydt.head(3 * n_) = y.tail(3 * n_);
    acceleration(t, y, dydt.tail(3 * n_));
  }
  void acceleration(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> a) const {
    a.setZero();
    add_spring_forces(springs_.view().springs, y.data(), y.data() + 3 * n_, a.data());
    a /= mass_;
    a -= drag_ * y.tail(3 * n_);
    for (int k = 0; k < n_; ++k) a[3 * k + 1] -= g_;
  }

  void sparse_jacobian(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::SparseMatrix<double>& dfdy) const override {
    Eigen::SparseMatrix<double> dfdx, dfdv;
    springs_.force_jacobians(y.data(), y.data() + 3 * n_, false, dfdx, dfdv);
    mass_spring_jacobian(dfdx, dfdv, springs_.view().mass, dfdy);
  }

  std::optional<double> energy(const Eigen::VectorXd& y) const override {
    double e = mass_ * y.tail(3 * n_).squaredNorm() / 2 + spring_energy(springs_.view().springs, y.data());
    for (int k = 0; k < n_; ++k) e += mass_ * g_ * y[3 * k + 1];
    return e;
  }

  std::vector<std::string> summary_names() const override {
    auto names = state_names();
    names.insert(names.end(), {"y_bottom", "energy"});
    return names;
  }
  Eigen::VectorXd summary(const Eigen::VectorXd& y) const override {
    Eigen::VectorXd s(y.size() + 2);
    s << y, y[3 * (n_ - 1) + 1], *energy(y);
    return s;
  }

 private:
  int n_;
  double mass_, drag_, g_;
  SecondOrderView second_order_;  // y = (x, v), with the acceleration below
  SpringNetwork springs_;  // the elastic forces and the drag's Jacobian
  Eigen::VectorXd y0_;
};

}  // namespace

std::span<const ParamSpec> hanging_chain_params() { return hanging_chain_specs; }
double hanging_chain_columns(const Params& p) { return 6.0 * node_count(p) + 2; }

std::unique_ptr<Model> make_hanging_chain(const Params& p) { return std::make_unique<HangingChain>(p); }

std::vector<double> chain_equilibrium(int nodes, double mass, double stiffness, double rest_length, double g) {
  std::vector<double> y;
  double height = 0;
  for (int k = 1; k <= nodes; ++k) {
    height -= rest_length + mass * g * (nodes - k + 1) / stiffness;  // the spring above node k carries N - k + 1 masses
    y.push_back(height);
  }
  return y;
}

}  // namespace stepwise
