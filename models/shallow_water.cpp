#include "shallow_water.hpp"

#include "height_field.hpp"
#include "particle_common.hpp"

#include <fmt/format.h>

#include <cmath>

namespace stepwise {

namespace {

// per grid point: eta, u and w in up to 32 copies (an adaptive method's stages and history)
constexpr double bytes_per_point = 32 * 3 * 8;

class ShallowWater final : public Model {
 public:
  explicit ShallowWater(const Params& p)
      : n_(particle_count(p, "size", p.at("size") * bytes_per_point, "grid points per side")),
        cells_(static_cast<Eigen::Index>(n_) * n_),
        d_(p.at("spacing")),
        depth_(p.at("depth")),
        g_(p.at("g")),
        mu_(p.at("mu")),
        x_(p.at("drop_x")),
        y_(p.at("drop_y")),
        radius_(p.at("drop_radius")),
        height_(p.at("drop_height")) {
    check_water_grid(p, n_, d_, true);
    if (!(height_ > -depth_))
      throw BadParameter("drop_height", fmt::format("parameter 'drop_height' = {} m would empty the pool (depth {} m)", height_, depth_));
  }

  std::string_view name() const override { return "shallow-water"; }
  int size() const override { return static_cast<int>(3 * cells_); }
  bool autonomous() const override { return true; }

  std::vector<std::string> state_names() const override {
    std::vector<std::string> names;
    for (const char* q : {"eta", "u", "w"})
      for (int i = 0; i < n_; ++i)
        for (int j = 0; j < n_; ++j) names.push_back(fmt::format("{}[{},{}]", q, i, j));
    return names;
  }

  Eigen::VectorXd initial_state() const override {
    Eigen::VectorXd y = Eigen::VectorXd::Zero(size());
    add_raised_cosine(n_, d_, x_, y_, radius_, height_, y.data());
    return y;
  }

  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    s.water = Shapes::Water{n_, d_, y.head(cells_)};
    return s;
  }

  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    const double* eta = y.data();
    const double* u = eta + cells_;
    const double* w = u + cells_;
    dydt.setZero();
    double* d_eta = dydt.data();
    double* du = d_eta + cells_;
    double* dw = du + cells_;
    // a face's value, 0 where there is no face (its slots hold 0, and past the grid there is none)
    const auto at = [this](const double* f, int i, int j) { return i < 0 || j < 0 || i >= n_ || j >= n_ ? 0.0 : f[i * n_ + j]; };
    const auto k = [this](int i, int j) { return static_cast<Eigen::Index>(i) * n_ + j; };
    // mass: the fluxes h u through the x-faces (i + 1/2, j) and h w through the y-faces (i, j + 1/2)
    const auto flux_x = [&](int i, int j) { return (depth_ + (eta[k(i, j)] + eta[k(i + 1, j)]) / 2) * u[k(i, j)]; };
    const auto flux_y = [&](int i, int j) { return (depth_ + (eta[k(i, j)] + eta[k(i, j + 1)]) / 2) * w[k(i, j)]; };
    for (int i = 1; i < n_ - 1; ++i)
      for (int j = 1; j < n_ - 1; ++j)
        d_eta[k(i, j)] = -((flux_x(i, j) - flux_x(i - 1, j)) + (flux_y(i, j) - flux_y(i, j - 1))) / d_;
    // momentum on the x-faces (i = 0 .. n-2, interior rows j) and the y-faces (interior columns i, j = 0 .. n-2)
    for (int i = 0; i < n_ - 1; ++i)
      for (int j = 1; j < n_ - 1; ++j) {
        const double cross = (at(w, i, j - 1) + at(w, i, j) + at(w, i + 1, j - 1) + at(w, i + 1, j)) / 4;
        const double advection = u[k(i, j)] * (at(u, i + 1, j) - at(u, i - 1, j)) / (2 * d_) + cross * (at(u, i, j + 1) - at(u, i, j - 1)) / (2 * d_);
        du[k(i, j)] = -g_ * (eta[k(i + 1, j)] - eta[k(i, j)]) / d_ - advection - mu_ * u[k(i, j)];
      }
    for (int i = 1; i < n_ - 1; ++i)
      for (int j = 0; j < n_ - 1; ++j) {
        const double cross = (at(u, i - 1, j) + at(u, i, j) + at(u, i - 1, j + 1) + at(u, i, j + 1)) / 4;
        const double advection = cross * (at(w, i + 1, j) - at(w, i - 1, j)) / (2 * d_) + w[k(i, j)] * (at(w, i, j + 1) - at(w, i, j - 1)) / (2 * d_);
        dw[k(i, j)] = -g_ * (eta[k(i, j + 1)] - eta[k(i, j)]) / d_ - advection - mu_ * w[k(i, j)];
      }
  }

  // per unit density and area element: g eta^2 / 2 at the points, h u^2 / 2 on the faces (h the face's depth)
  std::optional<double> energy(const Eigen::VectorXd& y) const override {
    const double* eta = y.data();
    const double* u = eta + cells_;
    const double* w = u + cells_;
    double potential = 0, kinetic = 0;
    for (int i = 0; i < n_; ++i)
      for (int j = 0; j < n_; ++j) {
        const Eigen::Index c = static_cast<Eigen::Index>(i) * n_ + j;
        potential += eta[c] * eta[c];
        if (i + 1 < n_) kinetic += (depth_ + (eta[c] + eta[c + n_]) / 2) * u[c] * u[c];
        if (j + 1 < n_) kinetic += (depth_ + (eta[c] + eta[c + 1]) / 2) * w[c] * w[c];
      }
    return d_ * d_ * (g_ * potential + kinetic) / 2;
  }

  std::vector<std::string> summary_names() const override { return {"energy", "max_abs_z"}; }
  Eigen::VectorXd summary(const Eigen::VectorXd& y) const override {
    Eigen::VectorXd s(2);
    s << *energy(y), y.head(cells_).cwiseAbs().maxCoeff();
    return s;
  }

 private:
  int n_;               // grid points per side
  Eigen::Index cells_;  // n^2
  double d_, depth_, g_, mu_;
  double x_, y_, radius_, height_;  // the drop
};

}  // namespace

std::span<const ParamSpec> shallow_water_params() {
  static const std::vector<ParamSpec> specs{
      {"size", 64, "", "grid points per side, boundary included (eta = 0 there); at least 3", Bound::positive},
      {"spacing", 0.02, "m", "grid spacing d", Bound::positive},
      {"depth", 0.1, "m", "rest depth H (the linear waves' speed is sqrt(g H))", Bound::positive},
      {"g", 9.81, "m/s^2", "gravity", Bound::positive},
      {"mu", 0.5, "1/s", "linear drag on the velocity (the wave equation's viscous damping)", Bound::nonnegative},
      {"drop_x", 0.4, "m", "drop centre, x (inside the grid)"},
      {"drop_y", 0.5, "m", "drop centre, y (inside the grid)"},
      {"drop_radius", 0.1, "m", "drop radius R", Bound::positive},
      {"drop_height", -0.005, "m", "surface height of the raised cosine at the centre (negative: a dent; above -depth)"}};
  return specs;
}

std::unique_ptr<Model> make_shallow_water(const Params& params) { return std::make_unique<ShallowWater>(params); }

}  // namespace stepwise
