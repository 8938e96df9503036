#include "chain.hpp"

#include "particle_common.hpp"
#include "solvers/capabilities/distance_constraints.hpp"
#include "solvers/capabilities/second_order.hpp"

#include <Eigen/SparseCholesky>
#include <fmt/format.h>

#include <array>

namespace stepwise {
namespace {

constexpr std::array chain_specs{
    ParamSpec{"links", 20, "", "rigid links from the pin", Bound::positive},
    ParamSpec{"length", 1.0, "m", "the chain's length", Bound::positive},
    ParamSpec{"mass", 1.0, "kg", "the chain's mass", Bound::positive},
    ParamSpec{"g", 9.81, "m/s^2", "gravitational acceleration", Bound::positive},
    ParamSpec{"baumgarte", 0, "", "Baumgarte stabilisation of the links' equations (1: on, --constraint baumgarte)", Bound::flag},
};

// a link's state, its constraint and the multipliers' sparse system: well under 1 KiB
int link_count(const Params& p) { return particle_count(p, "links", 1024, "links"); }

class Chain final : public Model {
 public:
  explicit Chain(const Params& p)
      : n_(link_count(p)), link_(p.at("length") / n_), mass_(p.at("mass") / n_), g_(p.at("g")),
        baumgarte_(p.at("baumgarte") == 1 ? baumgarte_rate(g_, link_) : 0.0) {
    constraints_.dimension = 2;
    constraints_.inverse_mass.assign(static_cast<size_t>(n_), 1 / mass_);
    for (int j = 0; j < n_; ++j) constraints_.constraints.push_back(DistanceConstraint{j, j - 1, Eigen::Vector3d::Zero(), link_, 0.0});
    constraints_.external = [this](double, const double*, const double*, double* a) {
      for (int i = 0; i < n_; ++i) a[2 * i] = 0, a[2 * i + 1] = -g_;
    };
  }
  std::string_view name() const override { return "chain"; }
  int size() const override { return 4 * n_; }
  bool autonomous() const override { return true; }
  std::vector<std::string> state_names() const override {
    std::vector<std::string> names;
    for (const char* v : {"", "v"})
      for (int i = 1; i <= n_; ++i) names.push_back(fmt::format("{}x{}", v, i)), names.push_back(fmt::format("{}y{}", v, i));
    return names;
  }
  Eigen::VectorXd initial_state() const override {
    Eigen::VectorXd y = Eigen::VectorXd::Zero(4 * n_);
    for (int i = 0; i < n_; ++i) y[2 * i] = (i + 1) * link_;
    return y;
  }
  const void* capability(const std::type_info& type) const override { return offer(type, second_order_, constraints_); }

  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    const auto x = [&](int i) { return i < 0 ? Eigen::Vector2d::Zero().eval() : Eigen::Vector2d(y[2 * i], y[2 * i + 1]); };
    const auto v = [&](int i) { return i < 0 ? Eigen::Vector2d::Zero().eval() : Eigen::Vector2d(y[2 * n_ + 2 * i], y[2 * n_ + 2 * i + 1]); };
    const double w = 1 / mass_;
    // d_j = x_j - x_{j-1}; gravity accelerates both ends alike, so d_j . (a_j - a_{j-1}) = 0 but at the pin
    std::vector<Eigen::Vector2d> d(static_cast<size_t>(n_));
    for (int j = 0; j < n_; ++j) d[static_cast<size_t>(j)] = x(j) - x(j - 1);
    std::vector<Eigen::Triplet<double>> entries;
    Eigen::VectorXd b(n_);
    const Eigen::Vector2d gravity(0, -g_);
    for (int j = 0; j < n_; ++j) {
      const Eigen::Vector2d& dj = d[static_cast<size_t>(j)];
      entries.emplace_back(j, j, (j == 0 ? w : 2 * w) * dj.squaredNorm());
      if (j + 1 < n_) {
        const double off = -w * dj.dot(d[static_cast<size_t>(j + 1)]);
        entries.emplace_back(j, j + 1, off);
        entries.emplace_back(j + 1, j, off);
      }
      b[j] = -(v(j) - v(j - 1)).squaredNorm() - dj.dot(j == 0 ? gravity : Eigen::Vector2d::Zero().eval());
      // Baumgarte: g_j'' held at -2 w g_j' - w^2 g_j (0 without it)
      b[j] -= 2 * baumgarte_ * dj.dot(v(j) - v(j - 1)) + baumgarte_ * baumgarte_ * 0.5 * (dj.squaredNorm() - link_ * link_);
    }
    Eigen::SparseMatrix<double> A(n_, n_);
    A.setFromTriplets(entries.begin(), entries.end());
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
    const Eigen::VectorXd lambda = solver.solve(b);
    dydt.head(2 * n_) = y.tail(2 * n_);
    for (int i = 0; i < n_; ++i) {
      Eigen::Vector2d a = gravity + w * lambda[i] * d[static_cast<size_t>(i)];
      if (i + 1 < n_) a -= w * lambda[i + 1] * d[static_cast<size_t>(i + 1)];
      dydt.segment<2>(2 * n_ + 2 * i) = a;
    }
  }
  std::optional<double> energy(const Eigen::VectorXd& y) const override {
    double e = 0;
    for (int i = 0; i < n_; ++i) e += 0.5 * mass_ * y.segment<2>(2 * n_ + 2 * i).squaredNorm() + mass_ * g_ * y[2 * i + 1];
    return e;
  }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    Eigen::Vector3d last = Eigen::Vector3d::Zero();
    for (int i = 0; i < n_; ++i) {
      const Eigen::Vector3d next(y[2 * i], y[2 * i + 1], 0);
      s.lines.push_back({last, next});
      last = next;
    }
    s.balls.push_back({last, 0.02 * link_ * n_, false});
    s.up = Eigen::Vector3d::UnitY();
    s.planar = true;
    return s;
  }

 private:
  int n_;
  double link_, mass_, g_;
  double baumgarte_;  // w (1/s), 0: off
  SecondOrderView second_order_{2 * n_};
  DistanceConstraints constraints_;
};

}  // namespace

std::span<const ParamSpec> chain_params() { return chain_specs; }

std::unique_ptr<Model> make_chain(const Params& p) { return std::make_unique<Chain>(p); }

double chain_columns(const Params& p) { return 4.0 * link_count(p) + 1; }

}  // namespace stepwise
