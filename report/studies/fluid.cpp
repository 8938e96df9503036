// The report's study: the incompressible fluid: Stable Fluids' numerical viscosity by grid and step, its order,
// and where the explicit methods' steps are limited on the pseudo-spectral method of lines.
#include "report/studies.hpp"

#include "models/model.hpp"
#include "verification/fluid_checks.hpp"
#include "verification/stability.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace stepwise {
namespace {

// the Taylor-Green vortex of the study: L = 1 m, mode 1 (k = 2 pi), A = 1 m/s; energy halves by the exact decay in
// ln 2 / (4 nu k^2) = 4.4 s at nu = 1e-3
constexpr double study_viscosity = 1e-3;
constexpr double viscosity_t_end = 1.0;

StudyOutput numerical_viscosity(const StudyContext& ctx, std::string& md, std::vector<Figure>& figures) {
  const std::vector<int> sizes = ctx.quick ? std::vector<int>{16, 32, 64} : std::vector<int>{16, 32, 64, 128};
  const std::vector<double> cfls = ctx.quick ? std::vector<double>{2, 8} : std::vector<double>{0.25, 0.5, 1, 2, 4, 8};
  const std::vector<std::string> methods{"stable-fluids", "stable-fluids-maccormack"};
  struct Point {
    std::string method;
    int n;
    double cfl;
  };
  std::vector<Point> plan;
  std::vector<std::string> labels;
  // a point's cost goes as its steps times its cells, n / CFL x n^2 (MacCormack advects three times a step, the
  // projection's FFTs the same: about twice the first-order step); relative, the sweep learns the scale
  std::vector<double> costs;
  for (const auto& method : methods)
    for (const int n : sizes)
      for (const double cfl : cfls) {
        plan.push_back({method, n, cfl});
        labels.push_back(fmt::format("{} {}^2 CFL {:g}", method, n, cfl));
        costs.push_back(std::pow(n, 3) / cfl * (method == "stable-fluids" ? 1 : 2));
      }
  const auto found = ctx.sweep<double>(labels, [&](size_t i) {
    const Point& p = plan[i];
    // A h / d = CFL with A = 1 m/s and d = L / n
    return taylor_green_viscosity(p.method, p.n, study_viscosity, p.cfl / p.n, viscosity_t_end);
  }, costs);
  Table table{{"method", "size", "cfl", "dt", "nu_effective", "nu_effective_over_nu", "excess_order"}, {}};
  // the finest refinement's orders (bilinear), the excess at the finest grid, and how the step changes it there
  double finest_low = 1e9, finest_high = -1e9, coarse_cfl = 0, fine_cfl = 0, maccormack_fine = 0;
  for (size_t i = 0; i < plan.size(); ++i) {
    const Point& p = plan[i];
    // the order in space at this CFL: the excess nu_eff - nu against the grid's half as fine
    double order = std::numeric_limits<double>::quiet_NaN();
    if (i >= cfls.size() && plan[i - cfls.size()].method == p.method) {
      const double coarse = found[i - cfls.size()] - study_viscosity, fine = found[i] - study_viscosity;
      if (coarse > 0 && fine > 0) order = std::log2(coarse / fine);
    }
    table.rows.push_back({p.method, static_cast<long>(p.n), p.cfl, p.cfl / p.n, found[i], found[i] / study_viscosity, order});
    if (p.n != sizes.back()) continue;
    const double ratio = found[i] / study_viscosity;
    if (p.method == "stable-fluids") {
      finest_low = std::min(finest_low, order), finest_high = std::max(finest_high, order);
      if (p.cfl == cfls.front()) coarse_cfl = ratio;
      if (p.cfl == cfls.back()) fine_cfl = ratio;
    } else if (p.cfl == cfls.front()) {
      maccormack_fine = ratio;
    }
  }
  md += fmt::format(
      "### Stable Fluids' numerical viscosity\n\n"
      "The Taylor-Green vortex (L = 1 m, k = 2 pi, A = 1 m/s, nu = {:g} m^2/s) run to t = {:g} s by Stam's step at the fixed step "
      "h = CFL d / A on n^2 points; the viscosity its energy decay implies, E(t) = E(0) e^(-4 nu_eff k^2 t), against the true nu. "
      "The order is log2 of the excess nu_eff - nu on the grid half as fine at the same CFL number.\n\n",
      study_viscosity, viscosity_t_end);
  md += markdown_table(table, {{"method", "method"},
                               {"size", "n"},
                               {"cfl", "CFL", shown_as("{}")},
                               {"dt", "h (s)", shown_as("{:.4g}")},
                               {"nu_effective_over_nu", "nu_eff / nu", shown_as("{:.3g}")},
                               {"excess_order", "order", shown_as("{:.2f}")}});
  md += "\n";
  FigureSpec spec{.title = "Stable Fluids' numerical viscosity",
                  .panels = {{.title = "{method}", .x_label = "grid points per side n", .y_label = "excess viscosity (nu_eff - nu) / nu", .log_x = true,
                              .log_y = true,
                              .layers = {{.table = "fluid_viscosity", .x = "size", .y = "nu_effective_over_nu", .series = "cfl", .label = "CFL {}",
                                          .y_of = "minus_one"}},
                              .guide_slope = -1, .guide_label = "first order (1/n)"}},
                  .facet = {"method"}};
  md += add_figure(figures, "fluid_viscosity", "", std::move(spec), "Stable Fluids' effective viscosity over the true one, by grid and CFL number");
  md += fmt::format(
      "\nBilinear semi-Lagrangian advection smooths the field by d^2 s (1 - s) / 2 a step (s the fraction of a cell the step "
      "moves it), an added viscosity of order d A at a fixed CFL number: first order in the grid. Measured, the order rises "
      "towards 1 as the grid is refined ({:.2f} to {:.2f} from {} to {} points a side). On {}^2 the method's own viscosity is "
      "still {:.3g} times the fluid's at CFL {:g} and {:.3g} times at CFL {:g}: the longer step adds the splitting and "
      "trajectory errors of the step itself, first order in h, to the interpolation's smoothing. On the grids an animation "
      "uses, the smoke's look is mostly the method's diffusion, not the fluid's. MacCormack's corrector removes the "
      "interpolation's leading error ({:.3g} times nu at CFL {:g} on {}^2), not the step's: at large CFL numbers it is no "
      "better.\n\n",
      finest_low, finest_high, sizes[sizes.size() - 2], sizes.back(), sizes.back(), coarse_cfl, cfls.front(), fine_cfl, cfls.back(),
      maccormack_fine, cfls.front(), sizes.back());
  return {{{"fluid_viscosity", std::move(table)}}, "", {}};
}

// one method's step limit on one viscosity: from the spectrum, the flow's own growth rate, measured
struct Found {
  double spectrum = 0, growth = 0, measured = 0;
  static auto fields(auto& s) { return std::tie(s.spectrum, s.growth, s.measured); }
};

StudyOutput step_limits(const StudyContext& ctx, std::string& md, std::vector<Figure>&) {
  // the Taylor-Green vortex on 16^2 points (512 unknowns: the Jacobian's spectrum is a dense eigenproblem), from
  // nearly inviscid (the advective limit binds) to strongly viscous (the viscous one does)
  const int n = 16;
  const long steps = ctx.quick ? 500 : 4000;
  const std::vector<double> viscosities = ctx.quick ? std::vector<double>{1e-3, 0.1} : std::vector<double>{1e-3, 0.03, 0.1, 0.3};
  const std::vector<std::string> explicit_methods{"rk4", "euler"};
  struct Point {
    std::string method;
    double nu;
  };
  std::vector<Point> plan;
  std::vector<std::string> labels;
  for (const double nu : viscosities)
    for (const auto& method : explicit_methods) {
      plan.push_back({method, nu});
      labels.push_back(fmt::format("{} nu {:g}", method, nu));
    }
  // the Jacobian's spectrum at the start, once per viscosity (both methods read it)
  std::vector<std::string> spectrum_labels;
  for (const double nu : viscosities) spectrum_labels.push_back(fmt::format("spectrum nu {:g}", nu));
  const auto spectra = ctx.sweep<Eigen::VectorXcd>(spectrum_labels, [&](size_t i) {
    const auto model = unit_taylor_green(n, viscosities[i]);
    return Eigen::VectorXcd(jacobian_spectrum(*model, 0, model->initial_state()));
  });
  const auto found = ctx.sweep<Found>(labels, [&](size_t i) {
    const Point& p = plan[i];
    const Eigen::VectorXcd& eigenvalues = spectra[i / explicit_methods.size()];
    // the flow's own instabilities (eigenvalues with Re > 0: the cells of the nearly inviscid vortex are unstable)
    // grow at any step; the step's limit is where the numerical growth begins, with them set on the axis
    const Eigen::VectorXcd numerical = eigenvalues.unaryExpr([](std::complex<double> l) { return std::complex<double>(std::min(l.real(), 0.0), l.imag()); });
    const double spectrum = spectrum_stable_dt(p.method, numerical).value_or(0);
    // max (|u| + |v|) of the vortex is A
    const double closed = fluid_step_limits(p.method, n, 1, 1, p.nu)->combined;
    return Found{spectrum, eigenvalues.real().maxCoeff(), taylor_green_measured_stable_dt(p.method, n, p.nu, steps, closed)};
  });
  Table table{{"nu", "method", "largest_growth", "advective_dt", "viscous_dt", "combined_dt", "spectrum_dt", "measured_dt", "measured_over_combined",
               "measured_over_spectrum"}, {}};
  // viscous rows (no growth of the flow's own): measured against the spectrum; the nearly inviscid row's figures
  double worst = 0, growth = 0, rk4_spectrum = 0, rk4_closed = 0, euler_closed = 0;
  for (size_t i = 0; i < plan.size(); ++i) {
    const Point& p = plan[i];
    const FluidStepLimits l = *fluid_step_limits(p.method, n, 1, 1, p.nu);
    const double nan = std::numeric_limits<double>::quiet_NaN(), spectrum = found[i].spectrum > 0 ? found[i].spectrum : nan;
    table.rows.push_back({p.nu, p.method, found[i].growth, l.advective, l.viscous, l.combined, spectrum, found[i].measured,
                          found[i].measured / l.combined, found[i].measured / spectrum});
    if (p.nu == viscosities.front()) {
      growth = found[i].growth;
      if (p.method == "rk4") rk4_spectrum = found[i].measured / spectrum, rk4_closed = found[i].measured / l.combined;
      else euler_closed = found[i].measured / l.combined;
    } else {
      worst = std::max(worst, std::abs(found[i].measured / spectrum - 1));
    }
  }
  md += fmt::format(
      "### Where the explicit methods' steps are limited\n\n"
      "The Taylor-Green vortex (A = 1 m/s) on {0}^2 points by the pseudo-spectral method of lines. The closed-form limits "
      "come from the highest mode the 2/3 rule keeps, |kx| = |ky| = kmax = 2 pi floor({0}/3), with frozen coefficients: "
      "advection alone gives it the eigenvalue i (u kx + v ky), at most i kmax max(|u| + |v|) = i A kmax (the advective CFL limit, h below the method's reach up the imaginary axis over it: none for "
      "explicit Euler), viscosity alone -nu 2 kmax^2 (the viscous limit), and the two together their sum. Beside them the "
      "limit from the whole spectrum of the Jacobian at the start, and the measured one (bisection to 0.1%: {1} steps stay "
      "within 1e6 of the start).\n\n",
      n, steps);
  md += markdown_table(table, {{"nu", "nu (m^2/s)", shown_as("{}")},
                               {"method", "method"},
                               {"largest_growth", "max Re lambda (1/s)", shown_as("{:.3g}")},
                               {"advective_dt", "advective (s)", shown_as("{:.4g}")},
                               {"viscous_dt", "viscous (s)", shown_as("{:.4g}")},
                               {"combined_dt", "both (s)", shown_as("{:.4g}")},
                               {"spectrum_dt", "spectrum (s)", shown_as("{:.4g}")},
                               {"measured_dt", "measured (s)", shown_as("{:.4g}")},
                               {"measured_over_combined", "measured / both", shown_as("{:.3g}")},
                               {"measured_over_spectrum", "measured / spectrum", shown_as("{:.3f}")}});
  md += fmt::format(
      "\nWith viscosity (nu >= {:g}) the measured limits are the spectrum's to {:.1f}%, and the viscous limit binds: it falls "
      "as 1/n^2 where the advective one falls as 1/n, the reason the viscosity is the part to take implicitly (an IMEX split), "
      "and Stable Fluids, implicit in both, has no limit at all (stable at CFL 20 in the suite). Nearly inviscid (nu = {:g}) "
      "the vortex's cells are themselves unstable: the Jacobian's eigenvalues reach Re lambda = {:.2f}/s, a growth no step "
      "removes, so the spectrum's limit is taken with those real parts set to 0. rk4's measured limit is then {:.2f} times the "
      "spectrum's (near its boundary on the imaginary axis |R| grows so slowly that {} steps hardly show it) and {:.2f} times "
      "the frozen-coefficient CFL bound, which is safe: a disturbance at the highest mode kept does not meet the largest speed "
      "everywhere. Explicit Euler has no stable step on an undamped advective mode (the spectrum's column is empty for it); "
      "it lives only where the viscosity damps the highest modes faster than advection grows them, h < 2a / (a^2 + b^2) for "
      "lambda = -a + i b, and measures {:.2f} times that closed form: the square of about the same overestimate of b "
      "(sqrt = {:.2f}) as rk4's.\n\n",
      viscosities[1], 100 * worst, viscosities.front(), growth, rk4_spectrum, steps, rk4_closed, euler_closed, std::sqrt(euler_closed));
  return {{{"fluid_step_limits", std::move(table)}}, "", {}};
}

StudyOutput fluid(const StudyContext& ctx) {
  std::string md = fmt::format(
      "The incompressible Navier-Stokes equations on a periodic square: Stam's Stable Fluids against the exact decay of the "
      "Taylor-Green vortex, and the explicit methods on the pseudo-spectral method of lines. The work-precision diagrams of "
      "the Taylor-Green vortex and the shear layer are in the work-precision section{}, with every method that applies; "
      "every fixed-step method's order on the vortex is in the convergence section.\n\n",
      ctx.quick ? " of the full report (`stepwise report` without --quick)" : "");
  std::vector<Figure> figures;
  StudyOutput out;
  for (auto* part : {numerical_viscosity, step_limits}) {
    StudyOutput o = part(ctx, md, figures);
    for (auto& t : o.tables) out.tables.push_back(std::move(t));
  }
  out.markdown = md;
  out.figures = figures;
  return out;
}

}  // namespace

Study fluid_study() { return {"fluid", "Fluid: Stable Fluids' own viscosity, and the explicit methods' step limits", fluid}; }

}  // namespace stepwise
