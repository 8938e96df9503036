// The report's study: spatial convergence of a PDE scene (model = "pde"): the scene run on grids of n, 2n, 4n, ...
// points, to its end in time, by a method at a tolerance far below the grid's error, and the error against its
// [exact] (or, without one, against the finest grid at the nodes it shares with each coarser one: Richardson's
// estimate of the coarser grid's error) fitted for the order the stencils reach, at the stencils' order 2 and 4.
#include "report/studies/study_scenes.hpp"
#include "report/user_scene.hpp"
#include "run/scene.hpp"
#include "verification/order_fit.hpp"

namespace stepwise {
namespace {

// the time integration, far below every grid's error: a stiff scene's fine grids want an implicit method (on
// heat-1d at order 4, 129 points, the grid's error is 1.2e-9 and cvode-bdf's at rtol 1e-13 a few 1e-12)
constexpr std::string_view method = "cvode-bdf";
constexpr double rtol = 1e-13, atol = 1e-15;

// one grid's run: its state at t_end (on the nodes) and how it ended
struct GridRun {
  Eigen::VectorXd y;
  std::string status;
  double exact_error = NAN;  // max over the grid against [exact], where the scene has one
  static auto fields(auto& s) { return std::tie(s.y, s.status, s.exact_error); }
};

// the study's own scenes: the shipped heat equations, one with Dirichlet sides, one periodic
std::vector<StudyScene> own_scenes() {
  std::vector<StudyScene> scenes;
  for (const char* name : {"heat-1d", "heat-periodic"}) {
    RunOptions options;
    options.scene_file = scenes_directory() + "/" + name + ".toml";
    scenes.push_back(user_study_scene(options));
  }
  return scenes;
}

// the grids: n0 2^k points (+1 where an axis has both ends as nodes, so that the coarser grids' nodes are the finer's)
std::vector<int> grid_points(bool periodic, int grids) {
  std::vector<int> points;
  for (int k = 0; k < grids; ++k) points.push_back((32 << k) + (periodic ? 0 : 1));
  return points;
}

// the coarse grid's values against the finest's at the nodes they share (each axis's every 2^k-th node)
double richardson_error(const Eigen::VectorXd& coarse, const Eigen::VectorXd& fine, const PdeGrid& coarse_grid, const PdeGrid& fine_grid) {
  const int stride = (fine_grid.nx - (fine_grid.nx % 2)) / (coarse_grid.nx - (coarse_grid.nx % 2));
  double worst = 0;
  for (size_t f = 0; f < coarse_grid.fields.size(); ++f)
    for (int j = 0; j < coarse_grid.ny; ++j)
      for (int i = 0; i < coarse_grid.nx; ++i) {
        const int at = (coarse_grid.ny > 1 ? j * stride * fine_grid.nx : 0) + i * stride;
        worst = std::max(worst, std::abs(coarse[static_cast<Eigen::Index>(f) * coarse_grid.nodes() + j * coarse_grid.nx + i] -
                                         fine[static_cast<Eigen::Index>(f) * fine_grid.nodes() + at]));
      }
  return worst;
}

StudyOutput spatial_convergence(const StudyContext& ctx) {
  const int grids = ctx.quick ? 3 : 4;
  Table points{{"scene", "stencil_order", "points", "h", "error", "error_against", "status"}, {}};
  Table orders{{"scene", "stencil_order", "observed_order", "finest_pair_order", "coarsest_error", "finest_error"}, {}};
  StudyOutput out;
  out.markdown = fmt::format(
      "Each PDE scene is run on grids of n, 2n, 4n{} points an axis to its end by {} at rtol {:g} (its time error far "
      "below every grid's), and its max error over the grid at t_end is measured against its [exact], or, without one, "
      "against the finest grid at the nodes they share. The observed order is the least-squares slope of log(error) against "
      "log(h) (beside it the slope between the two finest grids: a side's ghosts at order 4 err an order below the interior, "
      "and their error term settles later than the interior's), at the stencils' order 2 and 4 (five points an axis, a side's ghosts exact on quartics); an upwinded operator is "
      "first order whatever the stencils' order.\n\n",
      grids > 3 ? ", 8n" : "", method, rtol);
  const std::vector<StudyScene> scenes = scenes_or(ctx, own_scenes());
  // the points: a scene's grids at each stencil order
  struct Point {
    const StudyScene* scene;
    int order, points;
  };
  std::vector<Point> plan;
  std::vector<std::string> labels;
  for (const auto& scene : scenes) {
    for (const int order : {2, 4}) {
      for (const int n : grid_points(scene.periodic, grids)) {
        plan.push_back({&scene, order, n});
        labels.push_back(fmt::format("{} order {} {} points", scene.label, order, n));
      }
    }
  }
  const auto runs = ctx.sweep<GridRun>(labels, [&](size_t i) {
    const auto model = plan[i].scene->on_grid(plan[i].points, plan[i].order);
    const Measured m = run_and_measure(*model, std::string(method), StepControl::adaptive(rtol, atol), plan[i].scene->t_end, plan[i].scene->t_end);
    GridRun r{m.result.y_stop, std::string(to_string(m.result.status))};
    if (const PdeGrid* grid = pde_grid(*model); grid->exact && m.result.status == Status::ok)
      r.exact_error = (m.result.y_stop - grid->exact(plan[i].scene->t_end)).cwiseAbs().maxCoeff();
    return r;
  });
  // per scene and order: the errors, the fit
  for (size_t first = 0; first < plan.size();) {
    size_t last = first;
    while (last < plan.size() && plan[last].scene == plan[first].scene && plan[last].order == plan[first].order) ++last;
    const StudyScene& scene = *plan[first].scene;
    const bool exact = std::isfinite(runs[first].exact_error);
    // without [exact]: each coarser grid against the finest, at the nodes they share
    const auto finest_model = exact ? nullptr : scene.on_grid(plan[last - 1].points, plan[first].order);
    std::vector<double> h, error;
    for (size_t i = first; i < last; ++i) {
      double e = runs[i].exact_error;
      if (finest_model && i + 1 < last && runs[i].status == "ok" && runs[last - 1].status == "ok") {
        const auto model = scene.on_grid(plan[i].points, plan[i].order);
        e = richardson_error(runs[i].y, runs[last - 1].y, *pde_grid(*model), *pde_grid(*finest_model));
      }
      const double spacing = 1.0 / (plan[i].points - (scene.periodic ? 0 : 1));
      points.rows.push_back({scene.label, static_cast<long>(plan[i].order), static_cast<long>(plan[i].points), spacing, e,
                             std::string(exact ? "exact" : "finest grid"), runs[i].status});
      if (std::isfinite(e) && e > 0) {
        h.push_back(spacing);
        error.push_back(e);
      }
    }
    const double slope = h.size() >= 2 ? loglog_slope(h, error) : NAN;
    const size_t k = h.size();
    const double finest_pair = k >= 2 ? std::log(error[k - 2] / error[k - 1]) / std::log(h[k - 2] / h[k - 1]) : NAN;
    orders.rows.push_back({scene.label, static_cast<long>(plan[first].order), slope, finest_pair, error.empty() ? NAN : error.front(),
                           error.empty() ? NAN : error.back()});
    first = last;
  }
  FigureSpec spec{.title = "Spatial convergence: the max error at t_end against the grid's spacing",
                  .panels = {{.x_label = "h (in units of the domain)", .y_label = "max error at t_end", .log_x = true, .log_y = true,
                              .layers = {{.table = "spatial_convergence", .x = "h", .y = "error", .series = "scene", .split = {"stencil_order"},
                                          .split_dashed = true, .label = "{} (order {stencil_order})", .complete = {"error"}}}}}};
  out.markdown += add_figure(out.figures, "spatial_convergence", "", std::move(spec), "Spatial convergence of the PDE scenes");
  out.markdown += markdown_table(orders, {{"scene", "scene"},
                                          {"stencil_order", "stencils' order"},
                                          {"observed_order", "observed order", shown_as("{:.2f}")},
                                          {"finest_pair_order", "between the two finest grids", shown_as("{:.2f}")},
                                          {"coarsest_error", "error on the coarsest grid", shown_as("sci")},
                                          {"finest_error", "error on the finest", shown_as("sci")}});
  out.markdown += "\n";
  for (const auto& row : orders.rows)
    if (std::get<std::string>(row[0]) == "heat-periodic" && std::get<long>(row[1]) == 4)
      out.findings.push_back(fmt::format("**The text PDE's stencils reach their order**: the periodic heat equation converges in space at {:.2f} with "
                                         "order-4 stencils (spatial convergence).", std::get<double>(row[2])));
  out.tables = {{"spatial_convergence", std::move(points)}, {"spatial_convergence_orders", std::move(orders)}};
  return out;
}

}  // namespace

Study spatial_convergence_study() { return {.name = "spatial-convergence", .title = "Spatial convergence: your own PDE's stencils on refined grids", .run = spatial_convergence,
          .scene_problem = [](const StudyScene& scene, const Model&) {
            return scene.on_grid ? std::string() : std::string("is no PDE scene (model = \"pde\"): the spatial-convergence study refines a grid");
          }}; }

}  // namespace stepwise
