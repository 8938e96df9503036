#include "particle_system.hpp"

#include "solvers/capabilities/second_order.hpp"

#include "cell_list.hpp"
#include "particle_common.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

namespace stepwise {
namespace {

constexpr std::array particle_system_specs{
    ParamSpec{"count", 100000, "", "number of particles N", Bound::positive},
    ParamSpec{"seed", 1, "", "random seed of the initial state", Bound::nonnegative},
    ParamSpec{"spread", 1.0, "m", "initial positions are uniform in [-spread, spread]^3", Bound::positive},
    ParamSpec{"speed", 0.5, "m/s", "initial velocities are uniform in [-speed, speed]^3", Bound::nonnegative},
    ParamSpec{"stiffness", 4.0, "1/s^2", "stiffness k of the harmonic trap pulling each particle to the origin", Bound::positive},
    ParamSpec{"drag", 0.1, "1/s", "linear drag coefficient gamma", Bound::nonnegative},
    ParamSpec{"g", 9.81, "m/s^2", "gravitational acceleration along -z", Bound::nonnegative},
    ParamSpec{"repulsion", 0.0, "1/s^2", "stiffness s of the soft-sphere repulsion between particles; 0 switches it off", Bound::nonnegative},
    ParamSpec{"radius", 0.05, "m", "cut-off r_c of the repulsion: particles closer than this push apart", Bound::positive},
};

// per particle: six state entries in up to 32 copies (CVODE Adams keeps about 25 vectors, rk4 seven)
constexpr double particle_system_bytes_per_particle = 32 * 6 * 8;
constexpr double max_pairs = 1e8;

class ParticleSystem final : public Model, public SparseJacobian {
 public:
  explicit ParticleSystem(const Params& p)
      : n_(particle_count(p, "count", particle_system_bytes_per_particle)), seed_(particle_seed(p)), spread_(p.at("spread")),
        speed_(p.at("speed")), k_(p.at("stiffness")), gamma_(p.at("drag")), g_(p.at("g")), s_(p.at("repulsion")),
        rc_(p.at("radius")) {
    // the pairs within the cut-off, each evaluation of f: at the start, uniform in the cube of side 2 spread,
    // N^2 / 2 times the chance that two lie within r_c (the ball's share of the cube, at most 1); past 1e8 pairs
    // an evaluation takes seconds and a run days (the particles also crowd together in the trap)
    if (s_ > 0) {
      const double n = n_, share = std::min(1.0, 4.0 / 3.0 * std::numbers::pi * rc_ * rc_ * rc_ / std::pow(2 * spread_, 3));
      if (const double pairs = n * n / 2 * share; pairs > max_pairs)
        throw BadParameter("radius", fmt::format("parameter 'radius' = {} m puts about {:.3g} pairs of the {} particles within reach of "
                                                 "each other, more than {:.0e} each evaluation: a smaller radius or fewer particles",
                                                 rc_, pairs, n_, max_pairs));
    }
    second_order_.positions = 3 * n_;
    second_order_.acceleration = [this](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> a) { acceleration(t, y, a); };
    // without repulsion each coordinate's acceleration is its own: steppers may sweep in blocks
    if (s_ == 0)
      second_order_.local_acceleration = [this](double t, const double* x, const double* v, double* a, Eigen::Index first,
                                                Eigen::Index count) { local_acceleration(t, x, v, a, first, count); };
  }
  ParticleSystem(const ParticleSystem&) = delete;  // its capabilities hold `this`
  ParticleSystem& operator=(const ParticleSystem&) = delete;

  std::string_view name() const override { return "particle-system"; }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    s.balls = particle_balls(y, n_);
    return s;
  }
  int size() const override { return 6 * n_; }
  bool autonomous() const override { return true; }
  // the sparse Jacobian of the force field without interactions (s = 0)
  const void* capability(const std::type_info& type) const override {
    if (type == typeid(SparseJacobian)) return s_ == 0 ? &as_part<SparseJacobian>(*this) : nullptr;
    return offer(type, second_order_);
  }

  std::vector<std::string> state_names() const override { return particle_state_names(n_); }
  Eigen::VectorXd initial_state() const override {
    std::mt19937_64 rng(seed_);
    Eigen::VectorXd y(6 * n_);
    for (int k = 0; k < 3 * n_; ++k) y[k] = spread_ * (2 * uniform01(rng) - 1);
    for (int k = 0; k < 3 * n_; ++k) y[3 * n_ + k] = speed_ * (2 * uniform01(rng) - 1);
    return y;
  }

  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    dydt.head(3 * n_) = y.segment(3 * n_, 3 * n_);
    acceleration(t, y, dydt.segment(3 * n_, 3 * n_));
  }

  // the field, then the pairs the cell list finds
  void acceleration(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> a) const {
    const double* x = y.data();
    field(x, x + 3 * n_, a.data(), 0, 3L * n_);
    if (s_ == 0) return;
    CellList cells;
    cells.build(x, n_, rc_);
    cells.for_each_pair([&](int i, int j, const Eigen::Vector3d& d, double r2) {
      const double r = std::sqrt(r2);
      if (r == 0) return;  // coincident: no direction to push along
      const Eigen::Vector3d f = (s_ * (rc_ - r) / r) * d;
      a.segment<3>(3 * i) += f;
      a.segment<3>(3 * j) -= f;
    });
  }
  void local_acceleration(double, const double* x, const double* v, double* a, Eigen::Index first, Eigen::Index count) const {
    field(x, v, a, first, count);
  }

  // without repulsion df/dy has a fixed pattern: dx'/dv = I, dv'/dx = -k I, dv'/dv = -gamma I
  void sparse_jacobian(double, const Eigen::Ref<const Eigen::VectorXd>&, Eigen::SparseMatrix<double>& dfdy) const override {
    const int m = 3 * n_;
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(3 * static_cast<size_t>(m));
    for (int i = 0; i < m; ++i) {
      entries.emplace_back(i, m + i, 1.0);
      entries.emplace_back(m + i, i, -k_);
      entries.emplace_back(m + i, m + i, -gamma_);
    }
    dfdy.resize(2 * m, 2 * m);
    dfdy.setFromTriplets(entries.begin(), entries.end());
  }

  std::optional<double> energy(const Eigen::VectorXd& y) const override { return field_energy(y) + pair_energy(y).first; }

  std::vector<std::string> summary_names() const override {
    return {"energy", "kinetic", "centroid_x", "centroid_y", "centroid_z", "rms_radius", "max_speed", "contacts"};
  }
  Eigen::VectorXd summary(const Eigen::VectorXd& y) const override {
    const Eigen::Map<const Eigen::Matrix3Xd> x(y.data(), 3, n_), v(y.data() + 3 * n_, 3, n_);
    const Eigen::Vector3d centroid = x.rowwise().mean();
    const auto [pairs_energy, contacts] = pair_energy(y);
    Eigen::VectorXd s(8);
    s << field_energy(y) + pairs_energy, 0.5 * v.squaredNorm(), centroid,
        std::sqrt((x.colwise() - centroid).squaredNorm() / n_), v.colwise().norm().maxCoeff(), static_cast<double>(contacts);
    return s;
  }

  bool has_exact() const override { return s_ == 0; }
  Eigen::VectorXd exact(double t) const override {
    if (s_ != 0) return Model::exact(t);
    // the flow e^{At} of u'' + gamma u' + k u = 0 about the equilibrium
    const double delta = gamma_ * gamma_ / 4 - k_;
    double c = 1, s = t;
    if (delta < 0) {
      const double w = std::sqrt(-delta);
      c = std::cos(w * t);
      s = std::sin(w * t) / w;
    } else if (delta > 0) {
      const double q = std::sqrt(delta);
      c = std::cosh(q * t);
      s = std::sinh(q * t) / q;
    }
    const double decay = std::exp(-gamma_ * t / 2);
    Eigen::VectorXd y = initial_state();
    for (int i = 0; i < 3 * n_; ++i) {
      const double rest = i % 3 == 2 ? -g_ / k_ : 0.0;
      const double u0 = y[i] - rest, v0 = y[3 * n_ + i];
      y[i] = rest + decay * (c * u0 + s * (gamma_ / 2 * u0 + v0));
      y[3 * n_ + i] = decay * (c * v0 + s * (-k_ * u0 - gamma_ / 2 * v0));
    }
    return y;
  }

 private:
  // the trap, drag and gravity on coordinates [first, first + count) (x, v, a point at entry first)
  void field(const double* x, const double* v, double* a, Eigen::Index first, Eigen::Index count) const {
    const double k = k_, gamma = gamma_;
    for (Eigen::Index i = 0; i < count; ++i) a[i] = -k * x[i] - gamma * v[i];
    // gravity on the z entries (index 3 i + 2), a block's worth at a time while it is in cache
    for (Eigen::Index i = (2 - first % 3 + 3) % 3; i < count; i += 3) a[i] -= g_;
  }

  // kinetic energy and the trap's and gravity's potential energy
  double field_energy(const Eigen::VectorXd& y) const {
    return kinetic_and_gravity(y, g_) + 0.5 * k_ * y.head(3 * n_).squaredNorm();
  }

  // the repulsion's potential energy and the number of pairs within its reach
  std::pair<double, long> pair_energy(const Eigen::VectorXd& y) const {
    if (s_ == 0) return {0.0, 0};
    CellList cells;
    cells.build(y.data(), n_, rc_);
    double e = 0;
    long pairs = 0;
    cells.for_each_pair([&](int, int, const Eigen::Vector3d&, double r2) {
      const double gap = rc_ - std::sqrt(r2);
      e += 0.5 * s_ * gap * gap;
      ++pairs;
    });
    return {e, pairs};
  }

  int n_;
  unsigned long seed_;
  double spread_, speed_, k_, gamma_, g_, s_, rc_;
  SecondOrderView second_order_;  // y = (x, v), with the accelerations below
};

}  // namespace

std::span<const ParamSpec> particle_system_params() { return particle_system_specs; }

std::unique_ptr<Model> make_particle_system(const Params& p) { return std::make_unique<ParticleSystem>(p); }

}  // namespace stepwise
