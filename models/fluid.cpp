#include "fluid.hpp"

#include "particle_common.hpp"
#include "solvers/capabilities/fluid_grid.hpp"
#include "solvers/capabilities/imex_split.hpp"
#include "solvers/periodic_fft.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

namespace stepwise {

namespace {

using Complex = PeriodicFft::Complex;
using Modes = std::vector<Complex>;
constexpr double two_pi = 2 * std::numbers::pi;

// per grid point: u, v, rho in up to 32 copies (CVODE Adams keeps about 25 vectors) and the right-hand
// side's scratch (8 grid fields and 7 mode arrays)
constexpr double fluid_bytes_per_point = 32 * 3 * 8 + 8 * 8 + 7 * 16;

std::vector<ParamSpec> with_fluid_params(double viscosity, double size, std::initializer_list<ParamSpec> own) {
  std::vector<ParamSpec> specs{
      {"size", size, "", "grid points per side (periodic: no point repeated); at least 8", Bound::positive},
      {"length", 1.0, "m", "side L of the periodic square", Bound::positive},
      {"viscosity", viscosity, "m^2/s", "kinematic viscosity nu", Bound::nonnegative}};
  specs.insert(specs.end(), own);
  return specs;
}

// the parameter "size": a whole number of points per side whose run fits in memory, at least 8
int fluid_points(const Params& p) {
  const int n = particle_count(p, "size", p.at("size") * fluid_bytes_per_point, "grid points per side");
  if (n < 8) throw BadParameter("size", fmt::format("parameter 'size' must be at least 8 grid points per side, got {}", n));
  return n;
}

// the right-hand side's working arrays, one set per thread (a model may be evaluated from several), kept
// between calls: f allocates nothing once a size has been seen
struct Scratch {
  Modes U, V, R, A, B, C, tmp;
  std::vector<double> fields;
  void size_for(int modes, Eigen::Index points) {
    for (Modes* m : {&U, &V, &R, &A, &B, &C, &tmp}) m->resize(modes);
    fields.resize(8 * points);
  }
};

class Fluid final : public Model {
 public:
  enum class Flow { taylor_green, shear_wave, shear_layer, smoke };

  Fluid(Flow flow, const Params& p)
      : flow_(flow),
        n_(fluid_points(p)),
        cells_(static_cast<Eigen::Index>(n_) * n_),
        fft_(n_, p.at("length")) {
    grid_.points = n_;
    grid_.length = p.at("length");
    grid_.viscosity = p.at("viscosity");
    if (flow == Flow::taylor_green || flow == Flow::shear_wave) {
      const double m = p.at("mode");
      // the 2/3 rule keeps |wavenumber| <= K: a mode beyond it would be dropped from the start
      const int K = PeriodicFft::largest_kept(n_);
      if (m != std::floor(m) || m < 1 || m > K)
        throw BadParameter("mode", fmt::format("parameter 'mode' must be a whole number from 1 to (size - 1)/3 = {} (the modes the 2/3 rule keeps), got {}", K, m));
      mode_ = static_cast<int>(m);
      amplitude_ = p.at("amplitude");
    }
    if (flow == Flow::shear_layer) {
      width_ = p.at("width");
      perturbation_ = p.at("perturbation");
      amplitude_ = p.at("amplitude");
    }
    if (flow == Flow::smoke) {
      grid_.buoyancy = p.at("buoyancy");
      grid_.diffusivity = p.at("diffusivity");
      for (const char* key : {"source_x", "source_y"})
        if (!(p.at(key) >= 0 && p.at(key) < grid_.length))
          throw BadParameter(key, fmt::format("parameter '{}' = {} m puts the source outside the square [0, {} m)", key, p.at(key), grid_.length));
      // a Gaussian of the given radius (standard deviation), periodic images summed over the nearest ones
      source_.assign(cells_, 0.0);
      const double r = p.at("source_radius"), rate = p.at("source_rate"), d = fft_.spacing(), L = grid_.length;
      for (int i = 0; i < n_; ++i)
        for (int j = 0; j < n_; ++j) {
          double s = 0;
          for (int a = -1; a <= 1; ++a)
            for (int b = -1; b <= 1; ++b) {
              const double dx = j * d - p.at("source_x") + b * L, dy = i * d - p.at("source_y") + a * L;
              s += std::exp(-(dx * dx + dy * dy) / (2 * r * r));
            }
          source_[i * n_ + j] = rate * s;
        }
      // band-limited like everything the right-hand side makes
      Modes S(fft_.modes());
      fft_.forward(source_.data(), S.data());
      fft_.dealias(S.data());
      fft_.inverse(S.data(), source_.data());
      grid_.source = source_;
      source_modes_.resize(fft_.modes());
      fft_.forward(source_.data(), source_modes_.data());
    }
    density_ = flow == Flow::smoke;
    split_.stiff = "the viscosity and the density's diffusion";
    split_.linear = true;
    split_.implicit_part = [this](double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) { terms(y, f, false, true); };
    split_.explicit_part = [this](double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) { terms(y, f, true, false); };
    split_.implicit_solve = [this](double gamma, Eigen::Ref<Eigen::VectorXd> x) { implicit_solve(gamma, x); };
  }
  Fluid(const Fluid&) = delete;  // its capabilities hold `this`
  Fluid& operator=(const Fluid&) = delete;

  std::string_view name() const override {
    switch (flow_) {
      case Flow::taylor_green: return "taylor-green";
      case Flow::shear_wave: return "shear-wave";
      case Flow::shear_layer: return "shear-layer";
      case Flow::smoke: return "smoke";
    }
    return "";
  }
  int size() const override { return static_cast<int>(3 * cells_); }
  bool autonomous() const override { return true; }
  const void* capability(const std::type_info& type) const override { return offer(type, grid_, split_); }

  std::vector<std::string> state_names() const override {
    std::vector<std::string> names;
    for (const char* q : {"u", "v", "rho"})
      for (int i = 0; i < n_; ++i)
        for (int j = 0; j < n_; ++j) names.push_back(fmt::format("{}[{},{}]", q, i, j));
    return names;
  }

  Eigen::VectorXd initial_state() const override {
    if (has_exact()) return exact(0);
    Eigen::VectorXd y = Eigen::VectorXd::Zero(size());
    if (flow_ == Flow::shear_layer) {
      const double L = grid_.length, d = fft_.spacing();
      for (int i = 0; i < n_; ++i)
        for (int j = 0; j < n_; ++j) {
          const double x = j * d, yy = i * d;
          y[i * n_ + j] = amplitude_ * (yy <= L / 2 ? std::tanh(width_ * (yy - L / 4)) : std::tanh(width_ * (3 * L / 4 - yy)));
          y[cells_ + i * n_ + j] = perturbation_ * std::sin(two_pi * (x / L + 0.25));
        }
      // band-limited and divergence-free in the spectral sense, as the method of lines keeps it
      Modes U(fft_.modes()), V(fft_.modes());
      fft_.forward(y.data(), U.data());
      fft_.forward(y.data() + cells_, V.data());
      fft_.dealias(U.data());
      fft_.dealias(V.data());
      fft_.project(U.data(), V.data());
      fft_.inverse(U.data(), y.data());
      fft_.inverse(V.data(), y.data() + cells_);
    }
    return y;
  }

  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override { terms(y, dydt, true, true); }

 private:
  // f's terms: with `advective`, advection, buoyancy and the source (the IMEX split's explicit part); with
  // `viscous`, viscosity and the density's diffusion (its implicit part); with both, f. Every term is projected
  // and de-aliased with the rest, so the parts add up to f
  void terms(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt, bool advective, bool viscous) const {
    const int M = fft_.modes();
    const Eigen::Index P = cells_;
    thread_local Scratch scratch;
    scratch.size_for(M, P);
    // plain references, not a structured binding: clang 15 (the fuzz build) cannot capture one in a lambda
    Modes &U = scratch.U, &V = scratch.V, &R = scratch.R, &A = scratch.A, &B = scratch.B, &C = scratch.C, &tmp = scratch.tmp;
    std::vector<double>& fields = scratch.fields;
    fft_.forward(y.data(), U.data());
    fft_.forward(y.data() + P, V.data());
    fft_.dealias(U.data());
    fft_.dealias(V.data());
    // the fields the products need, on the grid: u, v and their derivatives (and rho's)
    double* u = fields.data();
    double* v = u + P;
    double* ux = v + P;
    double* uy = ux + P;
    double* vx = uy + P;
    double* vy = vx + P;
    const auto to_grid = [&](const Modes& a, int derivative, double* out) {
      for (int m = 0; m < M; ++m)
        tmp[m] = derivative == 0 ? a[m] : derivative == 1 ? fft_.d_dx(m, a[m]) : fft_.d_dy(m, a[m]);
      fft_.inverse(tmp.data(), out);
    };
    if (advective) {
      to_grid(U, 0, u), to_grid(V, 0, v), to_grid(U, 1, ux), to_grid(U, 2, uy), to_grid(V, 1, vx), to_grid(V, 2, vy);
      // (u . grad) u and (u . grad) v, in place of the derivatives they no longer need
      for (Eigen::Index k = 0; k < P; ++k) {
        ux[k] = u[k] * ux[k] + v[k] * uy[k];
        vx[k] = u[k] * vx[k] + v[k] * vy[k];
      }
      fft_.forward(ux, A.data());
      fft_.forward(vx, B.data());
    }
    const double nu = grid_.viscosity;
    for (int m = 0; m < M; ++m) {
      A[m] = advective ? -A[m] : Complex(0);
      B[m] = advective ? -B[m] : Complex(0);
      if (viscous) {
        A[m] -= nu * fft_.k2(m) * U[m];
        B[m] -= nu * fft_.k2(m) * V[m];
      }
    }
    if (density_) {
      double* rx = vy + P;
      double* ry = rx + P;
      fft_.forward(y.data() + 2 * P, R.data());
      fft_.dealias(R.data());
      if (advective) {
        to_grid(R, 1, rx), to_grid(R, 2, ry);
        for (Eigen::Index k = 0; k < P; ++k) rx[k] = u[k] * rx[k] + v[k] * ry[k];
        fft_.forward(rx, C.data());
      }
      const double kappa = grid_.diffusivity, b = grid_.buoyancy;
      for (int m = 0; m < M; ++m) {
        C[m] = advective ? -C[m] : Complex(0);
        if (viscous) C[m] -= kappa * fft_.k2(m) * R[m];
        if (advective) {
          C[m] += source_modes_[m];
          if (m != 0) B[m] += b * R[m];  // the mean density lifts nothing (Boussinesq about it)
        }
      }
      fft_.dealias(C.data());
      fft_.inverse(C.data(), dydt.data() + 2 * P);
    } else {
      dydt.tail(P).setZero();
    }
    fft_.dealias(A.data());
    fft_.dealias(B.data());
    fft_.project(A.data(), B.data());
    fft_.inverse(A.data(), dydt.data());
    fft_.inverse(B.data(), dydt.data() + P);
  }

  // x <- (1 - gamma df_I/dy)^-1 x for the implicit part, linear: in Fourier space df_I/dy is -nu |k|^2 Q with Q
  // the projection (Leray after the 2/3 rule; the 2/3 rule alone for the density, with kappa), so with QX and
  // X - QX apart, X = B - (gamma nu |k|^2 / (1 + gamma nu |k|^2)) Q B
  void implicit_solve(double gamma, Eigen::Ref<Eigen::VectorXd> x) const {
    const int M = fft_.modes();
    const Eigen::Index P = cells_;
    thread_local Scratch scratch;
    scratch.size_for(M, P);
    Modes &U = scratch.U, &V = scratch.V, &A = scratch.A, &B = scratch.B;
    const auto shrink = [&](Modes& full, const Modes& projected, double diffusivity) {
      for (int m = 0; m < M; ++m) {
        const double c = gamma * diffusivity * fft_.k2(m);
        full[m] -= c / (1 + c) * projected[m];
      }
    };
    fft_.forward(x.data(), U.data());
    fft_.forward(x.data() + P, V.data());
    A = U, B = V;
    fft_.dealias(A.data());
    fft_.dealias(B.data());
    fft_.project(A.data(), B.data());
    shrink(U, A, grid_.viscosity);
    shrink(V, B, grid_.viscosity);
    fft_.inverse(U.data(), x.data());
    fft_.inverse(V.data(), x.data() + P);
    if (density_) {
      fft_.forward(x.data() + 2 * P, U.data());
      A = U;
      fft_.dealias(A.data());
      shrink(U, A, grid_.diffusivity);
      fft_.inverse(U.data(), x.data() + 2 * P);
    }
  }

 public:
  std::optional<double> energy(const Eigen::VectorXd& y) const override {
    return 0.5 * fft_.spacing() * fft_.spacing() * y.head(2 * cells_).squaredNorm();
  }

  std::vector<std::string> summary_names() const override { return {"kinetic_energy", "enstrophy", "max_divergence", "density_total"}; }
  Eigen::VectorXd summary(const Eigen::VectorXd& y) const override {
    const int M = fft_.modes();
    Modes U(M), V(M), tmp(M);
    fft_.forward(y.data(), U.data());
    fft_.forward(y.data() + cells_, V.data());
    std::vector<double> w(cells_), div(cells_);
    vorticity(U, V, w.data());
    for (int m = 0; m < M; ++m) tmp[m] = fft_.divergence(m, U[m], V[m]);
    fft_.inverse(tmp.data(), div.data());
    const double dA = fft_.spacing() * fft_.spacing();
    double enstrophy = 0, max_div = 0;
    for (Eigen::Index k = 0; k < cells_; ++k) {
      enstrophy += w[k] * w[k];
      max_div = std::max(max_div, std::abs(div[k]));
    }
    Eigen::VectorXd s(4);
    s << *energy(y), 0.5 * dA * enstrophy, max_div, dA * y.tail(cells_).sum();
    return s;
  }

  // the smoke's density, or (a flow without one) the vorticity, as a picture over the square; y up
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override {
    Shapes s;
    s.planar = true;
    s.up = Eigen::Vector3d::UnitY();
    Shapes::Field field{.nx = n_, .ny = n_, .extent = Eigen::Vector2d::Constant(grid_.length), .values = Eigen::VectorXd(cells_), .is_signed = !density_};
    if (density_) {
      field.values = y.tail(cells_);
    } else {
      Modes U(fft_.modes()), V(fft_.modes());
      fft_.forward(y.data(), U.data());
      fft_.forward(y.data() + cells_, V.data());
      vorticity(U, V, field.values.data());
    }
    s.fields.push_back(std::move(field));
    return s;
  }

  bool has_exact() const override { return flow_ == Flow::taylor_green || flow_ == Flow::shear_wave; }
  Eigen::VectorXd exact(double t) const override {
    if (!has_exact()) return Model::exact(t);
    const double k = two_pi * mode_ / grid_.length, d = fft_.spacing();
    const double a = amplitude_ * std::exp(-(flow_ == Flow::taylor_green ? 2 : 1) * grid_.viscosity * k * k * t);
    Eigen::VectorXd y = Eigen::VectorXd::Zero(size());
    for (int i = 0; i < n_; ++i)
      for (int j = 0; j < n_; ++j) {
        const double x = j * d, yy = i * d;
        if (flow_ == Flow::taylor_green) {
          y[i * n_ + j] = a * std::sin(k * x) * std::cos(k * yy);
          y[cells_ + i * n_ + j] = -a * std::cos(k * x) * std::sin(k * yy);
        } else {
          y[i * n_ + j] = a * std::sin(k * yy);
        }
      }
    return y;
  }

 private:
  // w = v_x - u_y on the grid from the velocity's modes
  void vorticity(const Modes& U, const Modes& V, double* w) const {
    Modes tmp(fft_.modes());
    for (int m = 0; m < fft_.modes(); ++m) tmp[m] = fft_.d_dx(m, V[m]) - fft_.d_dy(m, U[m]);
    fft_.inverse(tmp.data(), w);
  }

  Flow flow_;
  int n_;
  Eigen::Index cells_;
  PeriodicFft fft_;
  FluidGridView grid_;
  ImexSplit split_;
  bool density_ = false;       // the density is carried (smoke): its transforms are done
  int mode_ = 0;
  double amplitude_ = 0, width_ = 0, perturbation_ = 0;
  std::vector<double> source_;  // s on the grid
  Modes source_modes_;          // and its modes
};

}  // namespace

std::span<const ParamSpec> taylor_green_params() {
  static const auto specs = with_fluid_params(0.01, 32, {
      {"mode", 1, "", "m: wavenumber k = 2 pi m / L, 1 <= m <= (size - 1)/3", Bound::positive},
      {"amplitude", 1.0, "m/s", "A: the velocity's initial amplitude"}});
  return specs;
}

std::span<const ParamSpec> shear_wave_params() {
  static const auto specs = with_fluid_params(0.01, 32, {
      {"mode", 1, "", "m: u = A sin(2 pi m y / L), 1 <= m <= (size - 1)/3", Bound::positive},
      {"amplitude", 1.0, "m/s", "A: the velocity's initial amplitude"}});
  return specs;
}

std::span<const ParamSpec> shear_layer_params() {
  static const auto specs = with_fluid_params(1e-4, 128, {
      {"width", 30, "1/m", "w: the layers' steepness (30: Brown & Minion's thick layer, 80: the thin one)", Bound::positive},
      {"perturbation", 0.05, "m/s", "d: amplitude of the cross-flow that starts the roll-up"},
      {"amplitude", 1.0, "m/s", "the layers' speed"}});
  return specs;
}

std::span<const ParamSpec> smoke_params() {
  static const auto specs = with_fluid_params(1e-4, 64, {
      {"buoyancy", 1.0, "m/s^2", "b: upward acceleration per unit density above the mean"},
      {"diffusivity", 1e-4, "m^2/s", "kappa: the density's diffusivity", Bound::nonnegative},
      {"source_x", 0.5, "m", "the source's centre, x"},
      {"source_y", 0.15, "m", "the source's centre, y"},
      {"source_radius", 0.04, "m", "the Gaussian source's standard deviation", Bound::positive},
      {"source_rate", 1.0, "1/s", "density added per second at the source's centre", Bound::nonnegative}});
  return specs;
}

std::unique_ptr<Model> make_taylor_green(const Params& p) { return std::make_unique<Fluid>(Fluid::Flow::taylor_green, p); }
std::unique_ptr<Model> make_shear_wave(const Params& p) { return std::make_unique<Fluid>(Fluid::Flow::shear_wave, p); }
std::unique_ptr<Model> make_shear_layer(const Params& p) { return std::make_unique<Fluid>(Fluid::Flow::shear_layer, p); }
std::unique_ptr<Model> make_smoke(const Params& p) { return std::make_unique<Fluid>(Fluid::Flow::smoke, p); }

}  // namespace stepwise
