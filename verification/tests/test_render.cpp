// Rendering: the photon map against closed forms (still water, flux, a sinusoid's paraxial caustic and its
// focus) and against an independent CPU photon tracer; frames against the simulation (a ball's centroid,
// a sheet's covered area, a field's colours its values, every scene drawn where its geometry projects); OSMesa
// and EGL giving the same bytes; golden frames on any llvmpipe thread count; the render command's contract (a
// 1-D PDE's space-time picture among it).
#include "render/caustics.hpp"
#include "render/renderer.hpp"
#include "render/water_optics.hpp"
#include "verification/photon_trace.hpp"
#include "verification/tolerances.hpp"
#include "models/model.hpp"
#include "app/run_command.hpp"
#include "run/measure.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>

#include <unistd.h>

#include <stb_image.h>  // libstb's decoder (the library render/image.cpp encodes with)

namespace stepwise {
namespace {

namespace fs = std::filesystem;

gl::Context& context() {
  static const std::unique_ptr<gl::Context> c = gl::make_osmesa_context();
  return *c;
}

// a square height field of `points` per side over [0, side]^2 from h(x, y)
Shapes::Water water_of(int points, double side, const std::function<double(double, double)>& h) {
  Shapes::Water w{points, side / (points - 1), Eigen::VectorXd(static_cast<Eigen::Index>(points) * points)};
  for (int i = 0; i < points; ++i)
    for (int j = 0; j < points; ++j) w.z[static_cast<Eigen::Index>(i) * points + j] = h(j * w.spacing, i * w.spacing);
  return w;
}

std::vector<float> photon_map(const Shapes::Water& water, const Eigen::Vector3d& light, double depth, int resolution) {
  render::PhotonMap map(context(), resolution);
  map.build(water, light, depth);
  return map.read();
}

TEST(Caustics, StillWaterIsUniformBeamTimesCosineTimesTransmittance) {
  const auto water = water_of(33, 1.0, [](double, double) { return 0.0; });
  const double tol = tolerance::still_photon_map(1.0, water.spacing);
  for (const double theta : {0.0, 0.5}) {
    const Eigen::Vector3d light(std::sin(theta), 0, std::cos(theta));
    const int m = 128;
    const auto map = photon_map(water, light, 0.25, m);
    const double expected = std::cos(theta) * render::fresnel_transmittance(std::cos(theta), render::water_index);
    // the beam refracted at theta_t shifts the lit square by depth tan(theta_t) towards -x: texels past that
    // band (and one texel more) are lit by exactly one triangle
    const double sin_t = std::sin(theta) / render::water_index, shift = 0.25 * sin_t / std::sqrt(1 - sin_t * sin_t);
    double worst = 0;
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j)
        if ((j + 0.5) / m < 1 - shift - 1.0 / m) worst = std::max(worst, std::abs(map[static_cast<size_t>(i) * m + j] / expected - 1));
    EXPECT_LE(worst, tol) << "theta = " << theta;
  }
}

TEST(Caustics, FluxOnTheFloorIsTheTransmittedPower) {
  // a Gaussian bump, still at the edges, under a vertical light, so that every ray lands on the floor (an
  // oblique beam would shift the lit square off the floor by depth tan(theta_t): measured 1.2% lost at 3 degrees)
  const auto water = water_of(65, 1.0, [](double x, double y) { return 0.01 * std::exp(-((x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5)) / 0.01); });
  const Eigen::Vector3d light = Eigen::Vector3d::UnitZ();
  // sum over the surface triangles of A cos(theta) T, in double
  double transmitted = 0;
  const int n = water.points;
  const auto p = [&](int i, int j) { return Eigen::Vector3d(j * water.spacing, i * water.spacing, water.z[i * n + j]); };
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j + 1 < n; ++j)
      for (const auto& tri : {std::array{p(i, j), p(i, j + 1), p(i + 1, j + 1)}, std::array{p(i, j), p(i + 1, j + 1), p(i + 1, j)}}) {
        const Eigen::Vector3d area = (tri[1] - tri[0]).cross(tri[2] - tri[0]) / 2;
        const double cos_i = area.normalized().dot(light);
        transmitted += area.norm() * cos_i * render::fresnel_transmittance(cos_i, render::water_index);
      }
  double previous = INFINITY;
  for (const int m : {64, 256, 1024}) {
    const auto map = photon_map(water, light, 0.2, m);
    double flux = 0;
    for (const float e : map) flux += e;
    flux /= static_cast<double>(m) * m;
    const double error = std::abs(flux / transmitted - 1);
    EXPECT_LE(error, tolerance::photon_flux(m)) << m << " texels a side";
    EXPECT_LE(error, previous) << "the error shrinks with the map's resolution";
    std::printf("flux on a %d^2 map: relative error %.3g\n", m, error);
    previous = error;
  }
}

// h = A sin(k x): under vertical light a ray from x lands at X = x + D (1 - 1/n) h'(x) (small slopes), so the
// floor's irradiance is T(1) / |1 + D (1 - 1/n) h''(x)|, focusing under the crests first at D = n / ((n - 1) A k^2)
struct Sinusoid {
  double A = 0.002, k = 4 * std::numbers::pi, n = render::water_index;
  double focus() const { return n / ((n - 1) * A * k * k); }
  // the paraxial irradiance at floor point X: x found from X by Newton's method
  double irradiance(double X, double D) const {
    const double c = D * (1 - 1 / n);
    double x = X;
    for (int it = 0; it < 50; ++it) x -= (x + c * A * k * std::cos(k * x) - X) / (1 - c * A * k * k * std::sin(k * x));
    return render::fresnel_transmittance(1, n) / std::abs(1 - c * A * k * k * std::sin(k * x));
  }
};

TEST(Caustics, SinusoidMatchesTheParaxialIntensity) {
  const Sinusoid s;
  const int points = 513, m = 512;
  const auto water = water_of(points, 1.0, [&](double x, double) { return s.A * std::sin(s.k * x); });
  const double D = 0.5 * s.focus();
  const auto map = photon_map(water, Eigen::Vector3d::UnitZ(), D, m);
  // I = I0 / (1 - r sin(kx)) with r = D / f: focusing r / (1 - r) at most, |d ln I / dx| = k r cos / (1 - r sin) at most k r / sqrt(1 - r^2)
  const double r = D / s.focus();
  const double tol = tolerance::paraxial_caustic(s.A, s.k, D, water.spacing, r / (1 - r), s.k * r / std::sqrt(1 - r * r));
  double worst = 0;
  const int row = m / 2;
  for (int j = m / 10; j < m - m / 10; ++j) {
    const double X = (j + 0.5) / m;
    worst = std::max(worst, std::abs(map[static_cast<size_t>(row) * m + j] / s.irradiance(X, D) - 1));
  }
  EXPECT_LE(worst, tol);
  std::printf("sinusoid at half the focal depth: worst relative error %.3g (bound %.3g)\n", worst, tol);
  // under a crest it is twice the still water's at half the focal depth
  EXPECT_NEAR(s.irradiance(0.125, D) / render::fresnel_transmittance(1, s.n), 2.0, 1e-12);
}

TEST(Caustics, FirstFocusUnderTheCrestsAtTheParaxialDepth) {
  // 1 / peak irradiance falls linearly in D, 1 - D / f: the line through the measured peaks meets zero at f
  const Sinusoid s;
  const int points = 513, m = 512;
  const auto water = water_of(points, 1.0, [&](double x, double) { return s.A * std::sin(s.k * x); });
  std::vector<double> depth, inverse;
  for (const double fraction : {0.3, 0.45, 0.6, 0.75}) {
    const double D = fraction * s.focus();
    const auto map = photon_map(water, Eigen::Vector3d::UnitZ(), D, m);
    double peak = 0;
    for (int j = m / 10; j < m - m / 10; ++j) peak = std::max(peak, static_cast<double>(map[static_cast<size_t>(m / 2) * m + j]));
    depth.push_back(D);
    inverse.push_back(render::fresnel_transmittance(1, s.n) / peak);
  }
  const double slope = (inverse.back() - inverse.front()) / (depth.back() - depth.front());
  const double focus = depth.front() - inverse.front() / slope;
  std::printf("first focus: %.6g m measured, %.6g m paraxial\n", focus, s.focus());
  EXPECT_NEAR(focus / s.focus(), 1.0, tolerance::paraxial_caustic(s.A, s.k, s.focus(), water.spacing, 1.0, 0.0));
}

TEST(Caustics, PhotonMapAgreesWithTheCpuPhotonTracer) {
  // two crossing waves and a bump, under an oblique light, binned 32 x 32
  const auto water = water_of(129, 1.0, [](double x, double y) {
    return 0.004 * std::sin(2 * std::numbers::pi * 2 * x) * std::sin(2 * std::numbers::pi * y) + 0.01 * std::exp(-((x - 0.4) * (x - 0.4) + (y - 0.6) * (y - 0.6)) / 0.02);
  });
  const Eigen::Vector3d light = Eigen::Vector3d(0.2, -0.1, 1).normalized();
  const double depth = 0.3;
  const int m = 512, bins = 32, per = m / bins;
  const auto map = photon_map(water, light, depth, m);
  const PhotonTrace trace = trace_photons(water, light, depth, bins, 4'000'000, 20261121);
  double max_z = 0, sum_z2 = 0;
  int counted = 0;
  for (int bi = 0; bi < bins; ++bi)
    for (int bj = 0; bj < bins; ++bj) {
      double mean = 0;
      for (int i = 0; i < per; ++i)
        for (int j = 0; j < per; ++j) mean += map[static_cast<size_t>(bi * per + i) * m + bj * per + j];
      mean /= per * per;
      const size_t b = static_cast<size_t>(bi) * bins + bj;
      // bins along the edge see rays leave the pool (the map clips them, the tracer too, differently)
      if (bi == 0 || bj == 0 || bi == bins - 1 || bj == bins - 1) continue;
      const double z = (mean - trace.irradiance[b]) / trace.sigma[b];
      max_z = std::max(max_z, std::abs(z));
      sum_z2 += z * z;
      ++counted;
    }
  std::printf("photon map against the tracer: max |z| %.3g, mean z^2 %.3g over %d bins\n", max_z, sum_z2 / counted, counted);
  EXPECT_LE(max_z, tolerance::photon_trace_max_z);
  EXPECT_LE(sum_z2 / counted, tolerance::photon_trace_mean_z2);
}

// the pixels of the ball's colour (red well above green)
Eigen::Vector3d red_pixels(const render::Image& image) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();  // x, y, count
  for (int r = 0; r < image.height; ++r)
    for (int c = 0; c < image.width; ++c) {
      const std::uint8_t* p = &image.rgba[(static_cast<size_t>(r) * image.width + c) * 4];
      if (p[0] > p[1] + 25) sum += Eigen::Vector3d(c + 0.5, r + 0.5, 1);
    }
  return sum;
}

TEST(Frames, BallCentroidIsWhereTheSimulationPutIt) {
  const auto model = make_model("bouncing-ball", {});
  const int w = 320, h = 240;
  Eigen::VectorXd y = model->initial_state();
  Eigen::VectorXd ground = y;
  ground[0] = 0;
  const std::vector<Shapes> span{*model->shapes(y), *model->shapes(ground)};
  const render::View view = render::make_view(span, {}, w, h);
  render::Renderer renderer(context(), w, h);
  for (const double height : {1.0, 0.6, 0.25, 0.0}) {
    y[0] = height;
    const Shapes shapes = *model->shapes(y);
    const auto sum = red_pixels(renderer.draw(shapes, {}, view));
    ASSERT_GT(sum.z(), 20) << "the ball is on screen";
    const Eigen::Vector2d centroid = sum.head<2>() / sum.z();
    const auto& ball = shapes.balls.front();
    const Eigen::Vector2d expected = view.camera.pixel(ball.center, w, h);
    const double distance = (view.camera.eye - ball.center).norm();
    EXPECT_LE((centroid - expected).norm(),
              tolerance::ball_centroid_px(ball.radius, distance, (expected - Eigen::Vector2d(w / 2.0, h / 2.0)).norm()))
        << "ball at height " << height;
  }
}

// the side-by-side videos' offset: a ball moved by d in the world is as many pixels off as the camera puts its
// two centres apart; a sheet against itself is 0 off; shapes without the same points have no offset
TEST(Frames, PixelDistanceIsTheLargestProjectedOffset) {
  const auto model = make_model("bouncing-ball", {});
  const int w = 320, h = 240;
  Eigen::VectorXd y = model->initial_state();
  const Shapes at = *model->shapes(y);
  y[0] -= 0.3;
  const Shapes moved = *model->shapes(y);
  const render::View view = render::make_view(std::vector<Shapes>{at, moved}, {}, w, h);
  const double expected = (view.camera.pixel(moved.balls[0].center, w, h) - view.camera.pixel(at.balls[0].center, w, h)).norm();
  ASSERT_GT(expected, 10) << "the move shows";
  EXPECT_NEAR(render::pixel_distance(at, moved, view.camera, w, h), expected, 1e-9 * expected);
  const auto cloth = make_model("cloth", {{"rows", 6}, {"columns", 6}});
  const Shapes sheet = *cloth->shapes(cloth->initial_state());
  EXPECT_EQ(render::pixel_distance(sheet, sheet, view.camera, w, h), 0);
  EXPECT_TRUE(std::isnan(render::pixel_distance(sheet, at, view.camera, w, h)));
}

TEST(Frames, FlatSheetCoversItsProjectedArea) {
  const Eigen::Index rows = 12, columns = 16;
  const auto model = make_model("cloth", {{"rows", rows}, {"columns", columns}});
  const int w = 320, h = 240;
  const Shapes shapes = *model->shapes(model->initial_state());
  const render::View view = render::make_view({&shapes, 1}, {}, w, h);
  render::Renderer renderer(context(), w, h);
  const auto image = renderer.draw(shapes, {}, view);
  // covered: not the background's grey (the sheet is red in front, blue behind)
  double covered = 0;
  for (size_t p = 0; p < image.rgba.size(); p += 4) {
    const int r = image.rgba[p], g = image.rgba[p + 1], b = image.rgba[p + 2];
    if (std::abs(r - g) > 12 || std::abs(b - g) > 12) ++covered;
  }
  // the projected triangles' areas (a flat sheet: they do not overlap) and the outline's length in pixels
  const TriangleMesh& sheet = shapes.surfaces.front();
  const auto px = [&](Eigen::Index v) { return view.camera.pixel(sheet.vertices.row(v).transpose(), w, h); };
  double area = 0;
  for (Eigen::Index f = 0; f < sheet.faces.rows(); ++f) {
    const Eigen::Vector2d a = px(sheet.faces(f, 0)), b = px(sheet.faces(f, 1)), c = px(sheet.faces(f, 2));
    area += std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x()) / 2;
  }
  const Eigen::Vector2d c00 = px(0), c01 = px(columns - 1), c10 = px((rows - 1) * columns), c11 = px(rows * columns - 1);
  const double outline = (c01 - c00).norm() + (c11 - c01).norm() + (c10 - c11).norm() + (c00 - c10).norm();
  ASSERT_GT(area, 1000) << "the sheet fills a good part of the frame";
  EXPECT_LE(std::abs(covered - area), tolerance::coverage_px(outline));
}

// the smoke-like colour map's red at s in [0, 1] (renderer.cpp's lit_fragment, mode 3), in 8-bit levels
double field_red(double s) { return 255 * (0.05 + (0.96 - 0.05) * std::clamp(s, 0.0, 1.0)); }

// a field of 8 x 4 nodes on a rectangle, not periodic, its value the node's column: each node's pixel has the
// colour of its value's place in the range given (a side's nodes at its edge), and a field after it beside it
TEST(Frames, AFieldsColourIsItsValueOnItsRange) {
  const int w = 320, h = 240, nx = 8, ny = 4;
  Shapes shapes;
  shapes.planar = true;
  shapes.up = Eigen::Vector3d::UnitY();
  Shapes::Field field{.nx = nx, .ny = ny, .origin = {1.0, 2.0}, .extent = {2.0, 1.0}, .periodic = {false, false}, .values = Eigen::VectorXd(nx * ny),
                      .range = std::array<double, 2>{-1.0, 8.0}};
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) field.values[j * nx + i] = i;
  shapes.fields.push_back(field);
  const render::View view = render::make_view({&shapes, 1}, {}, w, h);
  render::Renderer renderer(context(), w, h);
  const auto image = renderer.draw(shapes, {}, view);
  const auto red = [&](const Eigen::Vector2d& px) {
    const int x = std::clamp(static_cast<int>(px.x()), 0, w - 1), y = std::clamp(static_cast<int>(px.y()), 0, h - 1);
    return static_cast<double>(image.rgba[static_cast<size_t>(4 * (y * w + x))]);
  };
  const auto node = [&](int i, int j) {
    return view.camera.pixel(Eigen::Vector3d(1.0 + 2.0 * i / (nx - 1), 2.0 + 1.0 * j / (ny - 1), 0), w, h);
  };
  // the colour's change a pixel along a row: a node's step in the map over the pixels between two nodes
  const double per_pixel = (field_red(1.0 / 9) - field_red(0)) / (node(1, 1) - node(0, 1)).norm();
  for (int i = 0; i < nx; ++i) {
    // a side's node sits on the rectangle's edge: its pixel half inside, half in the background; taken a pixel in
    const Eigen::Vector2d at = node(i, 1) + Eigen::Vector2d(i == 0 ? 1.0 : i == nx - 1 ? -1.0 : 0.0, 0);
    EXPECT_NEAR(red(at), field_red((i + 1.0) / 9), tolerance::field_colour_levels(per_pixel) + (i == 0 || i == nx - 1 ? per_pixel : 0.0)) << "node " << i;
  }
}

// the pixels where `image` differs from `empty`, as a box [x0, x1) x [y0, y1); empty if none
struct PixelBox {
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  void extend(double x, double y) {
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
  bool empty() const { return x0 > x1; }
};

PixelBox changed_pixels(const render::Image& image, const render::Image& empty) {
  PixelBox box;
  for (int r = 0; r < image.height; ++r)
    for (int c = 0; c < image.width; ++c) {
      const size_t p = (static_cast<size_t>(r) * image.width + c) * 4;
      if (!std::equal(&image.rgba[p], &image.rgba[p] + 3, &empty.rgba[p])) {
        box.extend(c, r);
        box.extend(c + 1, r + 1);
      }
    }
  return box;
}

// where the shapes' geometry lands on screen: the drawn vertices of bodies, sheets and the pool's block, the balls'
// spheres (finely sampled: the drawn icospheres are inscribed in them), the rods' ends widened by their tubes
PixelBox projected_box(const Shapes& shapes, const render::View& view, int w, int h) {
  const Eigen::Matrix4d m = view.camera.view_projection(static_cast<double>(w) / h).cast<double>();
  PixelBox box;
  const auto add = [&](Eigen::Vector3d p, double widen_m = 0) {
    // a point under the ground (a resting contact's penetration) is seen where it meets the ground
    if (shapes.ground && !shapes.planar) {
      const Eigen::Vector3d n = shapes.ground->normal.normalized();
      p -= std::min(0.0, (p - shapes.ground->point).dot(n)) * n;
    }
    const Eigen::Vector4d clip = m * p.homogeneous();
    const double x = (clip.x() / clip.w() + 1) / 2 * w, y = (1 - clip.y() / clip.w()) / 2 * h;
    // a tube's radius in pixels at that distance
    const double widen = widen_m * m(1, 1) * h / 2 / clip.w();
    box.extend(x - widen, y - widen);
    box.extend(x + widen, y + widen);
  };
  const TriangleMesh sphere = sphere_mesh(1, 3);
  for (const auto& ball : shapes.balls)
    for (Eigen::Index v = 0; v < sphere.vertices.rows(); ++v)
      add(ball.center + (ball.radius > 0 ? ball.radius : view.point_radius) * sphere.vertices.row(v).transpose());
  for (const auto& body : shapes.bodies)
    for (Eigen::Index v = 0; v < body.mesh->vertices.rows(); ++v) add(body.rotation * body.mesh->vertices.row(v).transpose() + body.position);
  for (const auto& sheet : shapes.surfaces)
    for (Eigen::Index v = 0; v < sheet.vertices.rows(); ++v) add(sheet.vertices.row(v).transpose());
  for (const auto& line : shapes.lines)
    for (const auto& p : line) add(p, 0.35 * view.point_radius);
  for (const auto& field : shapes.fields)
    for (const double x : {field.origin.x(), field.origin.x() + field.extent.x()})
      for (const double y : {field.origin.y(), field.origin.y() + field.extent.y()}) add(Eigen::Vector3d(x, y, 0));
  if (shapes.water) {
    // the surround's corners, and the surface where it rises above the deck
    const render::Pool pool(*shapes.water, view.pool_depth);
    for (const double x : {-pool.border, pool.side + pool.border})
      for (const double y : {-pool.border, pool.side + pool.border})
        for (const double z : {-pool.depth, pool.rim}) add(Eigen::Vector3d(x, y, z));
    for (Eigen::Index k = 0; k < shapes.water->z.size(); ++k)
      if (shapes.water->z[k] > pool.rim)
        add(Eigen::Vector3d((k % shapes.water->points) * shapes.water->spacing, (k / shapes.water->points) * shapes.water->spacing, shapes.water->z[k]));
  }
  return box;
}

// every scene file, run a little way by its own method and drawn: the pixels that differ from the same view
// without the scene's objects (only its ground and container) fill the box the objects' geometry projects to
TEST(Frames, EverySceneIsDrawnWhereItsShapesProject) {
  const int w = 320, h = 180;
  render::Renderer renderer(context(), w, h);
  int scenes = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(STEPWISE_SOURCE_DIR) / "scenes")) {
    if (entry.path().extension() != ".toml") continue;
    ++scenes;
    const std::string name = entry.path().stem().string();
    RunOptions options;
    options.scene_file = entry.path().string();
    PreparedRun p = prepare_run(options);
    // a user's equations have nothing in space to draw (render refuses them: the bad-input catalogue)
    if (!p.model->shapes(p.model->initial_state())) {
      EXPECT_EQ(p.scene.model, "equations") << name << ": a model with nothing to draw";
      continue;
    }
    // a moment into the run: a quarter of it, at most 0.2 s (a hundred thousand particles take 40 ms a step)
    const double t = std::min(0.25 * p.t_end, 0.2);
    p.control.observe = [](const Eigen::VectorXd& y) { return y; };
    const Measured m = run_and_measure(*p.model, p.method, p.control, t, t);
    ASSERT_EQ(m.result.status, Status::ok) << name << ": " << m.result.message;
    const std::vector<Shapes> frames{*p.model->shapes(p.model->initial_state()), *p.model->shapes(m.result.trajectory.y.back())};
    const render::View view = render::make_view(frames, p.scene.look, w, h);
    for (const Shapes& shapes : frames) {
      Shapes scenery;
      scenery.ground = shapes.ground;
      scenery.container = shapes.container;
      scenery.up = shapes.up;
      scenery.planar = shapes.planar;
      const PixelBox drawn = changed_pixels(renderer.draw(shapes, {}, view), renderer.draw(scenery, {}, view));
      const PixelBox expected = projected_box(shapes, view, w, h);
      ASSERT_FALSE(drawn.empty()) << name;
      // each side no more than a pixel beyond the projected one, and reaching it to within a thin tip's
      // allowance; clipped to the frame (the view holds everything, but a ground line may run off it)
      const double outward = tolerance::silhouette_px, inward = tolerance::silhouette_tip_px;
      const PixelBox want{std::max(0.0, expected.x0), std::max(0.0, expected.y0), std::min<double>(w, expected.x1), std::min<double>(h, expected.y1)};
      const std::string where = fmt::format("{} at t = {}: drawn [{}, {}) x [{}, {}), projected [{:.1f}, {:.1f}] x [{:.1f}, {:.1f}]", name,
                                            &shapes == &frames.front() ? 0.0 : t, drawn.x0, drawn.x1, drawn.y0, drawn.y1, want.x0,
                                            want.x1, want.y0, want.y1);
      EXPECT_TRUE(drawn.x0 >= want.x0 - outward && drawn.x0 <= want.x0 + inward) << where;
      EXPECT_TRUE(drawn.y0 >= want.y0 - outward && drawn.y0 <= want.y0 + inward) << where;
      EXPECT_TRUE(drawn.x1 <= want.x1 + outward && drawn.x1 >= want.x1 - inward) << where;
      EXPECT_TRUE(drawn.y1 <= want.y1 + outward && drawn.y1 >= want.y1 - inward) << where;
    }
  }
  EXPECT_GE(scenes, 20);
}

TEST(Frames, OsmesaAndEglDrawTheSameBytes) {
  std::unique_ptr<gl::Context> egl;
  try {
    egl = gl::make_egl_context();
  } catch (const gl::GlError& e) {
    GTEST_SKIP() << "no EGL here: " << e.what();
  }
  const auto model = make_model("water-drop", {{"size", 32}});
  Eigen::VectorXd y = model->initial_state();
  const Shapes shapes = *model->shapes(y);
  const render::View view = render::make_view({&shapes, 1}, {}, 200, 150);
  std::string hashes[2];
  for (int k = 0; k < 2; ++k) {
    gl::Context& c = k == 0 ? *egl : context();
    render::Renderer renderer(c, 200, 150);
    hashes[k] = render::pixel_hash(renderer.draw(shapes, {}, view));
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

// ---- the command line

struct Command {
  int status;
  std::string err;
};

// stderr goes to a file of this process's own: CTest runs the render tests as parallel processes, and one
// shared name let one test read another's (empty) stderr
Command stepwise_render(const std::string& args, const std::string& environment = "") {
  static int calls = 0;
  const fs::path err = fs::temp_directory_path() / fmt::format("stepwise_render_err_{}_{}.txt", getpid(), ++calls);
  const int raw = std::system((environment + " " + STEPWISE_BIN + " render " + args + " 2> " + err.string()).c_str());
  std::string text;
  {
    std::ifstream in(err);
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  fs::remove(err);
  return {WEXITSTATUS(raw), text};
}

TEST(RenderCommand, WritesFramesTheirHashesAndAMovie) {
  const fs::path out = fs::temp_directory_path() / "stepwise_render_test";
  fs::remove_all(out);
  const std::string scene = std::string(STEPWISE_SOURCE_DIR) + "/scenes/pendulum.toml";
  const Command c = stepwise_render(scene + " --frames 5 --size 160x90 --out " + out.string());
  ASSERT_EQ(c.status, 0) << c.err;
  std::ifstream in(out / "render.json");
  const auto j = nlohmann::json::parse(in);
  ASSERT_EQ(j["frames"].size(), 5u);
  for (const auto& f : j["frames"]) EXPECT_TRUE(fs::exists(out / f["file"].get<std::string>()));
  EXPECT_EQ(j["status"], "ok");
  // a swinging pendulum: the frames differ
  EXPECT_NE(j["frames"][0]["hash"], j["frames"][2]["hash"]);
  if (std::system("command -v ffmpeg > /dev/null") == 0) {
    EXPECT_GT(fs::file_size(out / "animation.mp4"), 0u);
    EXPECT_GT(fs::file_size(out / "animation.gif"), 0u);
  }
  // the same frames again: byte for byte (deterministic)
  const fs::path again = out / "again";
  ASSERT_EQ(stepwise_render(scene + " --frames 5 --size 160x90 --backend egl --out " + again.string()).status, 0);
  std::ifstream in2(again / "render.json");
  const auto j2 = nlohmann::json::parse(in2);
  for (size_t k = 0; k < 5; ++k) EXPECT_EQ(j["frames"][k]["hash"], j2["frames"][k]["hash"]) << "frame " << k;
}

// a 1-D PDE's render: its curve's frames and space_time.png, the heat equation's mode over x (along) and t (up): at
// the middle of the domain its colour darkens up the picture as exp(-D pi^2 t) decays, and by the Dirichlet sides
// (u = 0, the range's low end) it is near the map's dark end throughout
TEST(RenderCommand, APdesFieldIsPicturedOverSpaceAndTime) {
  const fs::path out = fs::temp_directory_path() / fmt::format("stepwise_render_pde_{}", getpid());
  fs::remove_all(out);
  const Command c = stepwise_render(std::string(STEPWISE_SOURCE_DIR) + "/scenes/heat-1d.toml --frames 6 --size 160x120 --out " + out.string());
  ASSERT_EQ(c.status, 0) << c.err;
  std::ifstream in(out / "render.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["fields"], nlohmann::json::array({"u"}));
  ASSERT_EQ(j["space_time"], "space_time.png");
  int w = 0, h = 0, channels = 0;
  std::unique_ptr<unsigned char, decltype(&stbi_image_free)> pixels(stbi_load((out / "space_time.png").string().c_str(), &w, &h, &channels, 4), &stbi_image_free);
  ASSERT_TRUE(pixels) << stbi_failure_reason();
  const auto red = [&](int x, int y) { return static_cast<double>(pixels.get()[4 * (y * w + x)]); };
  // the picture fills the frame's width to within its 5% margin and is 0.75 of the domain high: rows from 20% to
  // 80% of the frame lie inside it, bottom (early) to top (late)
  std::vector<double> middle;
  for (const double f : {0.8, 0.65, 0.5, 0.35, 0.2}) middle.push_back(red(w / 2, static_cast<int>(f * h)));
  for (size_t k = 1; k < middle.size(); ++k) EXPECT_LT(middle[k], middle[k - 1]) << "row " << k;
  // u(1/2, t) runs from 1 (the map's light end) to exp(-0.1 pi^2) = 0.37 over the run
  EXPECT_GT(middle.front(), field_red(0.37));
  EXPECT_LT(middle.back(), field_red(0.95));
  // 5% of the frame in from its left, within 0.03 of the side x = 0: u <= sin(0.03 pi) = 0.094 at any time
  EXPECT_LT(red(static_cast<int>(0.05 * w), h / 2), field_red(0.094) + tolerance::field_colour_levels(0)) << "by the side u = 0";
}

// the golden frames (verification/golden/frames.json) drawn again on 1 and 3 llvmpipe threads: the same bytes
TEST(RenderCommand, FramesMatchTheirGoldenHashesOnAnyThreadCount) {
  std::ifstream in(fs::path(STEPWISE_SOURCE_DIR) / "verification/golden/frames.json");
  const auto golden = nlohmann::json::parse(in);
  const std::string renderer = context().description();
  if (renderer != golden["renderer"].get<std::string>())
    GTEST_SKIP() << "the golden hashes are for " << golden["renderer"] << "; this renderer is " << renderer;
  ASSERT_GE(golden["scenes"].size(), 5u);
  for (const auto& [scene, hashes] : golden["scenes"].items())
    for (const int threads : {1, 3}) {
      const fs::path out = fs::temp_directory_path() / ("stepwise_golden_" + scene);
      fs::remove_all(out);
      const Command c = stepwise_render(fmt::format("{}/scenes/{}.toml --frames {} --size {} --out {}", STEPWISE_SOURCE_DIR, scene,
                                                    golden["frames"].get<int>(), golden["size"].get<std::string>(), out.string()),
                                        fmt::format("LP_NUM_THREADS={}", threads));
      ASSERT_EQ(c.status, 0) << scene << ": " << c.err;
      std::ifstream drawn(out / "render.json");
      const auto j = nlohmann::json::parse(drawn);
      std::vector<std::string> measured;
      for (const auto& frame : j["frames"]) measured.push_back(frame["hash"]);
      EXPECT_EQ(measured, hashes.get<std::vector<std::string>>()) << scene << " on " << threads << " llvmpipe threads";
    }
}

TEST(RenderCommand, BadInputIsExitTwoNamingTheOption) {
  const std::string scene = std::string(STEPWISE_SOURCE_DIR) + "/scenes/pendulum.toml";
  const std::string out = (fs::temp_directory_path() / "stepwise_render_bad").string();
  for (const auto& [args, named] : std::vector<std::pair<std::string, std::string>>{
           {"--size 0x10", "--size"}, {"--size 20000x10", "--size"}, {"--size wide", "--size"},
           {"--backend vulkan", "--backend"}, {"--frames 0", "--frames"}}) {
    const Command c = stepwise_render(scene + " " + args + " --out " + out);
    EXPECT_EQ(c.status, 2) << args;
    EXPECT_NE(c.err.find(named), std::string::npos) << c.err;
    EXPECT_EQ(std::count(c.err.begin(), c.err.end(), '\n'), 1) << "one line: " << c.err;
  }
}

}  // namespace
}  // namespace stepwise
