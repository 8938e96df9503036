// stable-fluids: Stam's "Stable Fluids" (SIGGRAPH 1999) on the periodic grid of fluid_grid.hpp, one step of h:
//
//   1. forces      v += h b (rho - mean rho),  rho += h s
//   2. advection   q(x) <- q(x_back) for q = u, v, rho, semi-Lagrangian: x_back traced back through the
//                  velocity of step 1 by the midpoint rule (x_mid = x - h/2 u(x), x_back = x - h u(x_mid)),
//                  the value there bilinear in the four surrounding points (periodic): semi_lagrangian.hpp
//   3. diffusion   implicit Euler in Fourier space: q^ <- q^ / (1 + nu |k|^2 h) (kappa for rho)
//   4. projection  (u^, v^) <- P(u^, v^) (periodic_fft.hpp's Leray projection)
//
// Unconditionally stable (advection only ever interpolates, diffusion and projection only shrink modes),
// first order in time, and diffusive: bilinear interpolation damps a mode of wavenumber k by about
// 1 - (k d)^2 |frac| (1 - |frac|) / 2 per step, a numerical viscosity that the report measures on the
// Taylor-Green vortex.
//
// stable-fluids-maccormack: step 2 by Selle et al.'s MacCormack scheme (2008): the forward advection q^,
// its backward advection q~ (the same trace with -u), q = q^ + (q - q~) / 2, clamped to the four points
// the forward trace interpolated between (the limiter that keeps it from overshooting). Second order where
// the flow is smooth; the clamp makes it first order at extrema.
#include "solvers/capabilities/fluid_grid.hpp"
#include "solvers/fixed_step.hpp"
#include "solvers/method_table.hpp"
#include "solvers/periodic_fft.hpp"
#include "solvers/run_support.hpp"
#include "solvers/semi_lagrangian.hpp"

#include <algorithm>
#include <cmath>

namespace stepwise {

namespace {

using Complex = PeriodicFft::Complex;

class StableFluids final : public FixedStepper {
 public:
  StableFluids(const CountedSystem& s, bool maccormack)
      : system_(s), grid_(*s.as<FluidGridView>()), n_(grid_.points), cells_(static_cast<Eigen::Index>(n_) * n_),
        fft_(n_, grid_.length), maccormack_(maccormack), forced_(3 * cells_), back_x_(cells_), back_y_(cells_),
        modes_(fft_.modes()), modes_v_(fft_.modes()) {
    if (maccormack_) {
      ahead_.resize(cells_);
      behind_.resize(cells_);
      fore_x_.resize(cells_);
      fore_y_.resize(cells_);
    }
  }

  bool step(double, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    ++system_.stats().rhs_evals;  // one pass of the physics per step
    const Eigen::Index P = cells_;
    // 1. forces
    forced_ = y;
    double* u = forced_.data();
    double* v = u + P;
    double* rho = v + P;
    if (grid_.buoyancy != 0) {
      const double mean = forced_.tail(P).mean();
      for (Eigen::Index k = 0; k < P; ++k) v[k] += h * grid_.buoyancy * (rho[k] - mean);
    }
    if (!grid_.source.empty())
      for (Eigen::Index k = 0; k < P; ++k) rho[k] += h * grid_.source[k];
    // 2. advection through the forced velocity
    const double s = h / fft_.spacing();  // the step in grid units of time
    semi_lagrangian::trace(u, v, n_, s, back_x_.data(), back_y_.data());
    if (maccormack_) semi_lagrangian::trace(u, v, n_, -s, fore_x_.data(), fore_y_.data());
    for (int q = 0; q < 3; ++q) advect(forced_.data() + q * P, y_next.data() + q * P);
    // 3. diffusion and 4. projection in Fourier space
    double* u1 = y_next.data();
    double* v1 = u1 + P;
    double* rho1 = v1 + P;
    fft_.forward(u1, modes_.data());
    fft_.forward(v1, modes_v_.data());
    fft_.diffuse(modes_.data(), grid_.viscosity * h);
    fft_.diffuse(modes_v_.data(), grid_.viscosity * h);
    fft_.project(modes_.data(), modes_v_.data());
    fft_.inverse(modes_.data(), u1);
    fft_.inverse(modes_v_.data(), v1);
    if (grid_.diffusivity > 0) {
      fft_.forward(rho1, modes_.data());
      fft_.diffuse(modes_.data(), grid_.diffusivity * h);
      fft_.inverse(modes_.data(), rho1);
    }
    RunningNorm norm;
    for (Eigen::Index k = 0; k < 3 * P; ++k) norm.add(y_next[k]);
    norm_ = norm.value();
    return true;
  }

 private:
  // q carried along the traced points (semi_lagrangian.hpp's bilinear sample)
  double sample(const double* q, double x, double y, double* lo = nullptr, double* hi = nullptr) const {
    return semi_lagrangian::sample(q, n_, x, y, lo, hi);
  }

  void advect(const double* q, double* out) {
    if (!maccormack_) {
      for (Eigen::Index k = 0; k < cells_; ++k) out[k] = sample(q, back_x_[k], back_y_[k]);
      return;
    }
    for (Eigen::Index k = 0; k < cells_; ++k) ahead_[k] = sample(q, back_x_[k], back_y_[k]);
    for (Eigen::Index k = 0; k < cells_; ++k) behind_[k] = sample(ahead_.data(), fore_x_[k], fore_y_[k]);
    for (Eigen::Index k = 0; k < cells_; ++k) {
      double lo, hi;
      sample(q, back_x_[k], back_y_[k], &lo, &hi);
      out[k] = std::clamp(ahead_[k] + 0.5 * (q[k] - behind_[k]), lo, hi);
    }
  }

  const CountedSystem& system_;
  FluidGridView grid_;
  int n_;
  Eigen::Index cells_;
  PeriodicFft fft_;
  bool maccormack_;
  Eigen::VectorXd forced_;                         // the state after step 1
  std::vector<double> back_x_, back_y_;            // where each point's value comes from
  std::vector<double> fore_x_, fore_y_;            // where it goes (MacCormack's backward advection)
  std::vector<double> ahead_, behind_;             // MacCormack's forward and backward results
  std::vector<Complex> modes_, modes_v_;
};

}  // namespace

void register_stable_fluids_methods(MethodTable& table) {
  for (const bool maccormack : {false, true})
    table.add({
        .name = maccormack ? "stable-fluids-maccormack" : "stable-fluids",
        .family = Family::stable_fluids,
        .source = Source::hand_written,
        .description = maccormack ? "Stable Fluids with MacCormack advection (Selle et al. 2008, clamped): sharper smoke, same stability"
                                  : "Stam's Stable Fluids: forces, semi-Lagrangian advection (bilinear), diffusion and projection by FFT; fixed step",
        .order = maccormack ? Order{1, 2, "1-2"} : Order{1, 1, "1"},
        .stepping = Stepping::fixed,
        .needs = needs_fluid_grid,
        .make = fixed_steps([maccormack](const CountedSystem& system) { return std::make_unique<StableFluids>(system, maccormack); }),
    });
}

}  // namespace stepwise
