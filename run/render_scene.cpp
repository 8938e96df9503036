#include "render_scene.hpp"

#include "models/pde.hpp"
#include "render/renderer.hpp"
#include "run/atomic_write.hpp"
#include "run/measure.hpp"
#include "run/process.hpp"
#include "run/interrupt.hpp"
#include "run/message.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <mutex>

namespace stepwise {
namespace {

namespace fs = std::filesystem;

constexpr int max_side = 16384;  // GL_MAX_RENDERBUFFER_SIZE of llvmpipe

// "WxH" as two whole numbers in [1, max_side]
std::pair<int, int> parse_size(const std::string& text) {
  const auto x = text.find('x');
  int w = 0, h = 0;
  const auto whole = [](std::string_view s, int& v) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    return ec == std::errc() && end == s.data() + s.size();
  };
  if (x == std::string::npos || !whole(std::string_view(text).substr(0, x), w) || !whole(std::string_view(text).substr(x + 1), h))
    throw InputError(fmt::format("--size {}: expected WIDTHxHEIGHT in pixels, such as 1280x720", text));
  if (w < 1 || h < 1 || w > max_side || h > max_side)
    throw InputError(fmt::format("--size {}: each side must lie in 1..{} pixels", text, max_side));
  return {w, h};
}

// the run sampled every `interval` (a whole number of steps for a fixed-step method); every `stride`-th
// sample is a frame, the others only lengthen the trails, so a trail follows its path between frames (a
// pendulum sampled at frame rate alone shows its aliased zigzag)
struct Samples {
  std::vector<double> t;
  std::vector<Eigen::VectorXd> y;
  size_t stride = 1;
  RunResult result;
};

// when the samples and frames fall: every `interval` (whole steps), a frame every `stride` samples, `count` frames
struct FramePlan {
  double interval = 0;
  size_t stride = 1;
  int count = 1;
};

FramePlan plan_frames(const PreparedRun& p, int frames, bool trails) {
  FramePlan plan;
  plan.stride = trails ? 16 : 1;
  plan.interval = (frames > 1 ? p.t_end / (frames - 1) : p.t_end) / static_cast<double>(plan.stride);
  if (p.control.dt) {
    // whole steps, rounded down so that the frames asked for fit before t_end; fewer trail samples between
    // frames when the steps between them are fewer than the stride
    const double dt = *p.control.dt;
    const double steps_per_frame = std::floor((frames > 1 ? p.t_end / (frames - 1) : p.t_end) / dt * (1 + 1e-9));
    plan.stride = static_cast<size_t>(std::clamp<double>(steps_per_frame, 1, static_cast<double>(plan.stride)));
    plan.interval = std::max(1.0, std::floor(steps_per_frame / static_cast<double>(plan.stride))) * dt;
  }
  const double frame_interval = plan.interval * static_cast<double>(plan.stride);
  plan.count = frames > 1 ? static_cast<int>(std::min<double>(frames, 1 + std::floor(p.t_end / frame_interval * (1 + 1e-12)))) : 1;
  return plan;
}

Samples simulate(const PreparedRun& p, const FramePlan& plan) {
  const double frame_interval = plan.interval * static_cast<double>(plan.stride);
  StateSamples s = sample_states(*p.model, p.method, p.control, frame_interval * (plan.count - 1), plan.interval);
  return {std::move(s.t), std::move(s.y), plan.stride, std::move(s.result)};
}

// ffmpeg refuses a picture whose (width + 128)(height + 128) reaches INT_MAX / 8 (libavutil's
// av_image_check_size): 16384 x 16384 does, 16384 x 8192 does not (both tried here)
bool ffmpeg_takes(int width, int height) {
  return (static_cast<double>(width) + 128) * (static_cast<double>(height) + 128) < std::numeric_limits<int>::max() / 8;
}

// a frame of one colour shows nothing of the scene
bool one_colour(const render::Image& image) {
  const auto* p = reinterpret_cast<const std::uint32_t*>(image.rgba.data());
  const size_t n = image.rgba.size() / 4;
  return std::all_of(p, p + n, [first = p[0]](std::uint32_t v) { return v == first; });
}

// a camera that sees something: finite, the eye apart from the target, up not along the line of sight
void check_camera(const render::Camera& camera, const Scene& scene) {
  // the GL pipeline works in single precision: a point a billion metres out has no digits left for a picture
  constexpr double farthest = 1e9;
  for (const auto& [point, key] : {std::pair{camera.eye, "render.eye"}, std::pair{camera.target, "render.target"}})
    if (!(point.cwiseAbs().maxCoeff() <= farthest))
      throw InputError(fmt::format("{}: ({}, {}, {}) m is beyond {:.0e} m of the origin, where single-precision drawing has nothing to show",
                                   scene.where(key), point.x(), point.y(), point.z(), farthest));
  const Eigen::Vector3d sight = camera.target - camera.eye;
  const bool finite = camera.eye.allFinite() && camera.target.allFinite() && sight.allFinite() && camera.up.allFinite();
  if (!finite || !(sight.norm() > 0))
    throw InputError(fmt::format("{}: the camera's eye and target give no line of sight ({})", scene.where("render.eye"),
                                 finite ? "the same point" : "not finite"));
  if (!(sight.normalized().cross(camera.up.normalized()).norm() > 1e-6))
    throw InputError(fmt::format("{}: up is along the line of sight from the eye to the target: the picture has no up", scene.where("render.up")));
}

// ffmpeg's GIF (480 px wide, its own palette) and MP4 (H.264, even sides) from the PNGs, in one ffmpeg (the frames
// read once: 0.66 s where two took 0.80 on 12 small frames), each written to a temporary name and renamed
void encode_movies(const fs::path& dir, int fps) {
  if (!on_path("ffmpeg")) {
    print_error("render", "ffmpeg is not installed: wrote the PNG frames only (apt-get install ffmpeg for animation.mp4 and animation.gif)");
    return;
  }
  std::vector<std::pair<fs::path, fs::path>> written;  // temporary, target
  for (const char* name : {"animation.gif", "animation.mp4"}) written.emplace_back(dir / fmt::format(".{}.tmp", name), dir / name);
  const std::string gif = "scale=480:-1:flags=lanczos,split[a][b];[a]palettegen[p];[b][p]paletteuse";
  std::vector<std::string> args{"ffmpeg", "-y", "-loglevel", "error", "-framerate", std::to_string(fps), "-i", (dir / "frame_%04d.png").string()};
  args.insert(args.end(), {"-filter_complex", "[0:v]split[m][g];[m]pad=ceil(iw/2)*2:ceil(ih/2)*2[mp4];[g]" + gif + "[gif]", "-map", "[gif]", "-f", "gif",
                           written[0].first.string(), "-map", "[mp4]", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-f", "mp4", written[1].first.string()});
  std::string why;
  const auto status = run_process(args, &why);
  if (!status || *status != 0) {
    for (const auto& [temporary, target] : written) fs::remove(temporary);
    throw std::runtime_error(fmt::format("ffmpeg (animation.gif, animation.mp4) failed: {}", status ? fmt::format("exit status {}", *status) : why));
  }
  for (const auto& [temporary, target] : written) fs::rename(temporary, target);
}

// everything the inputs alone say, checked before a GL context is made or anything runs: the scene prepared as
// `run` takes it, the frame's size and backend, when the frames fall, and what they cost in memory and on disk
struct RenderPlan {
  PreparedRun p;
  int width = 0, height = 0;
  gl::Backend backend{};
  bool has_trails = false;
  FramePlan frames;
};

RenderPlan plan_render(const RenderOptions& options) {
  RenderPlan r;
  PreparedRun& p = r.p;
  std::pair<int, int> size;
  try {
    size = parse_size(options.size);
    const auto parsed = gl::parse_backend(options.backend);
    if (!parsed) throw InputError(fmt::format("--backend {}: unknown backend (osmesa or egl)", options.backend));
    r.backend = *parsed;
    if (options.frames < 1 || options.frames > 100000) throw InputError(fmt::format("--frames {}: must lie in 1..100000", options.frames));
    p = prepare_run(options.run);
    if (!p.model->shapes(p.model->initial_state()))
      throw InputError(fmt::format("{}: model {} has nothing to draw", p.scene.where("model"), p.scene.model));
    check_writable_directory(options.out);
    check_replaceable_file(fs::path(options.out) / "render.json");
    for (int k = 0; k < options.frames; ++k) check_replaceable_file(fs::path(options.out) / fmt::format("frame_{:04d}.png", k));
    check_replaceable_file(fs::path(options.out) / "space_time.png");
  } catch (const InputError&) {
    throw;
  } catch (const BadMethod& e) {
    throw InputError(fmt::format("{}: {}", p.scene.where("run.method"), e.what()));
  } catch (const std::runtime_error& e) {
    throw InputError(fmt::format("--out: {}", e.what()));
  }
  const auto [width, height] = size;
  r.width = width;
  r.height = height;
  const Shapes first = *p.model->shapes(p.model->initial_state());
  r.has_trails = std::any_of(first.balls.begin(), first.balls.end(), [](const Shapes::Ball& b) { return b.trail; });
  // what the frames asked for cost, before anything runs: every sample is kept for the frames and trails
  r.frames = plan_frames(p, options.frames, r.has_trails);
  const FramePlan& plan = r.frames;
  if (plan.count < options.frames)
    throw InputError(fmt::format("--frames {}: the run's step dt = {} s leaves room for only {} distinct frames up to t_end = {} s: ask for "
                                 "at most {}, or take a smaller --dt", options.frames, *p.control.dt, plan.count, p.t_end, plan.count));
  const double sample_bytes = (static_cast<double>(plan.count - 1) * static_cast<double>(plan.stride) + 1) * static_cast<double>(p.model->size()) * 8;
  if (over_memory_budget(sample_bytes))
    throw InputError(fmt::format("--frames {}: the frames' states would take {:.3g} GiB, {}", options.frames, sample_bytes / 0x1p30,
                                 memory_budget_text()));
  // the pixels' cost, before anything runs: the memory a frame takes to draw, read back and encode (measured
  // over the ~100 MB a render starts with, at the peak: 50-67 bytes a pixel from 2048^2 to 8192 x 4096 — the
  // GL's colour and depth buffers and llvmpipe's own, the read-back, the two frames the encoder may hold,
  // stb's filtered rows and its output), and the disk the frames will take (a PNG at most half of its 4 bytes a
  // pixel: the scenes' frames take 3-11%)
  constexpr double bytes_per_pixel = 72, png_share = 0.5;
  const double pixels = static_cast<double>(width) * height;
  if (over_memory_budget(bytes_per_pixel * pixels))
    throw InputError(fmt::format("--size {}: a frame takes about {:.3g} GiB to draw, read back and encode ({:.0f} bytes a pixel), {}",
                                 options.size, bytes_per_pixel * pixels / 0x1p30, bytes_per_pixel, memory_budget_text()));
  if (const auto free_bytes = free_bytes_at(options.out); free_bytes && png_share * 4 * pixels * plan.count > *free_bytes)
    throw InputError(fmt::format("--size {} and --frames {}: the frames may take up to {:.3g} GB (a PNG at most half of its 4 bytes a pixel), "
                                 "more than the {:.3g} GB free in {}", options.size, plan.count, png_share * 4 * pixels * plan.count / 1e9,
                                 *free_bytes / 1e9, options.out));
  return r;
}

// the frames: every stride-th sample, and the last one if the run stopped between frames (diverged)
struct Frames {
  std::vector<Shapes> shapes;
  std::vector<size_t> samples;  // the sample each frame shows
};

// the fields that hold one colour range over an animation get their least and greatest finite values over all
// of its frames
void hold_ranges(std::vector<Shapes>& frames) {
  for (size_t k = 0; k < frames.front().fields.size(); ++k) {
    if (!frames.front().fields[k].same_range) continue;
    std::array<double, 2> range{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    for (const auto& frame : frames)
      for (const double v : frame.fields[k].values)
        if (std::isfinite(v)) range = {std::min(range[0], v), std::max(range[1], v)};
    if (range[0] <= range[1])
      for (auto& frame : frames) frame.fields[k].range = range;
  }
}

Frames pick_frames(const PreparedRun& p, const Samples& samples) {
  Frames frames;
  for (size_t k = 0; k < samples.y.size(); ++k)
    if (k % samples.stride == 0 || k + 1 == samples.y.size()) frames.samples.push_back(k);
  for (const size_t k : frames.samples) frames.shapes.push_back(*p.model->shapes(samples.y[k]));
  hold_ranges(frames.shapes);
  return frames;
}

// a 1-D PDE's fields over space and time: each a picture with x along and the frames' times up (0.75 of the
// domain's length high), side by side; none for any other model or a single frame
std::optional<Shapes> space_time(const PreparedRun& p, const Samples& samples, const Frames& frames) {
  const PdeGrid* grid = pde_grid(*p.model);
  if (!grid || grid->ny > 1 || frames.samples.size() < 2) return std::nullopt;
  Shapes s;
  s.planar = true;
  s.up = Eigen::Vector3d::UnitY();
  const double length = grid->domain[0][1] - grid->domain[0][0];
  const auto rows = static_cast<int>(frames.samples.size());
  for (size_t f = 0; f < grid->fields.size(); ++f) {
    Shapes::Field field{.nx = grid->nx, .ny = rows, .origin = {grid->domain[0][0] + drawn_offset(*grid, f), 0}, .extent = {length, 0.75 * length},
                        .periodic = {grid->periodic[0], false}, .values = Eigen::VectorXd(Eigen::Index{grid->nx} * rows), .same_range = true};
    for (int r = 0; r < rows; ++r)
      field.values.segment(Eigen::Index{r} * grid->nx, grid->nx) = samples.y[frames.samples[static_cast<size_t>(r)]].segment(static_cast<Eigen::Index>(f) * grid->nx, grid->nx);
    s.fields.push_back(std::move(field));
  }
  std::vector<Shapes> one{std::move(s)};
  hold_ranges(one);
  return std::move(one.front());
}

// render.json's facts of the run and the picture, before its frames
nlohmann::json render_facts(const PreparedRun& p, const Samples& samples, const RenderOptions& options, const RenderPlan& planned,
                            const gl::Context& context, const render::Camera& camera, double simulate_seconds) {
  nlohmann::json summary;
  summary["scene"] = p.scene.name;
  summary["model"] = std::string(p.model->name());
  summary["method"] = p.method;
  summary["status"] = std::string(to_string(samples.result.status));
  summary["message"] = samples.result.message.empty() ? nlohmann::json(nullptr) : nlohmann::json(samples.result.message);
  summary["width"] = planned.width;
  summary["height"] = planned.height;
  summary["backend"] = options.backend;
  summary["renderer"] = context.description();
  summary["simulate_seconds"] = simulate_seconds;
  if (const PdeGrid* grid = pde_grid(*p.model)) summary["fields"] = grid->fields;  // a PDE's, as its pictures place them
  summary["camera"] = {{"eye", {camera.eye.x(), camera.eye.y(), camera.eye.z()}},
                       {"target", {camera.target.x(), camera.target.y(), camera.target.z()}},
                       {"up", {camera.up.x(), camera.up.y(), camera.up.z()}},
                       {"fov_deg", camera.fov_deg}};
  summary["frames"] = nlohmann::json::array();
  return summary;
}

// the balls' trails up to frame f's sample: `sampled` counts the samples already on them
void extend_trails(std::vector<std::vector<Eigen::Vector3d>>& trails, size_t& sampled, const PreparedRun& p, const Samples& samples,
                   const Frames& frames, size_t f) {
  for (; sampled <= frames.samples[f]; ++sampled) {
    const Shapes at = sampled == frames.samples[f] ? frames.shapes[f] : *p.model->shapes(samples.y[sampled]);
    size_t trail = 0;
    for (const auto& ball : at.balls)
      if (ball.trail) {
        if (trails.size() <= trail) trails.emplace_back();
        trails[trail++].push_back(ball.center);
      }
  }
}

// a frame of a few pixels is one colour whatever the camera sees (a 1 x 1 frame always): said as such
void say_empty_frames(size_t empty_frames, size_t frames, int width, int height) {
  constexpr double fewest_telling_pixels = 32 * 32;
  if (empty_frames == 0) return;
  print_error("render", static_cast<double>(width) * height < fewest_telling_pixels
                            ? fmt::format("{} of {} frames show one colour only: a {} x {} frame is too small to show the scene", empty_frames,
                                          frames, width, height)
                            : fmt::format("{} of {} frames show one colour only: the scene is outside the camera's view (see render.json's camera)",
                                          empty_frames, frames));
}

}  // namespace

void check_render(const RenderOptions& options) { plan_render(options); }

RenderedRun render_scene(const RenderOptions& options) {
  RenderPlan planned = plan_render(options);
  PreparedRun& p = planned.p;
  const int width = planned.width, height = planned.height;
  const gl::Backend backend = planned.backend;
  const bool has_trails = planned.has_trails;
  const FramePlan& plan = planned.frames;
  const fs::path out(options.out);

  std::unique_ptr<gl::Context> context;
  try {
    context = gl::make_context(backend);
  } catch (const gl::GlError& e) {
    throw InputError(fmt::format("--backend {}: {}", options.backend, e.what()));
  }
  const bool movies = ffmpeg_takes(width, height);
  if (!movies && options.frames > 1)
    print_error("render", fmt::format("--size {}: larger than ffmpeg takes ((width + 128)(height + 128) must stay below 2^28): writing the "
                                      "PNG frames only", options.size));
  const auto start = std::chrono::steady_clock::now();
  Samples samples = simulate(p, plan);
  const double simulate_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const Frames frames = pick_frames(p, samples);
  const std::vector<Shapes>& shapes = frames.shapes;
  // one view for the whole animation: the union of the frames' bounds
  const render::View view = render::make_view(shapes, p.scene.look, width, height);
  check_camera(view.camera, p.scene);
  try {
    ensure_writable_directory(out);
    interrupt::remove_stale(out);
  } catch (const std::runtime_error& e) {
    throw InputError(fmt::format("--out: {}", e.what()));
  }

  // render.json: the run's and the picture's facts, then the frames as their PNGs are written; an interruption
  // writes it with the frames finished so far
  nlohmann::json summary = render_facts(p, samples, options, planned, *context, view.camera, simulate_seconds);
  std::mutex summary_mutex;
  std::vector<nlohmann::json> drawn;  // each frame's entry, joining summary["frames"] once its PNG is written
  const interrupt::OnInterrupt last_words([&] {
    std::lock_guard lock(summary_mutex);
    nlohmann::json partial = summary;
    partial["status"] = "interrupted";
    write_file_atomic(out / "render.json", partial.dump(2) + "\n");
  });
  size_t empty_frames = 0;

  try {
    render::Renderer renderer(*context, width, height);
    render::EncodeQueue queue([&](size_t k, const std::string& png) {
      write_file_atomic(out / fmt::format("frame_{:04d}.png", k), png);
      std::lock_guard lock(summary_mutex);
      summary["frames"].push_back(drawn[k]);
    });
    std::vector<std::vector<Eigen::Vector3d>> trails;
    drawn.reserve(shapes.size());  // entries stay where they are while the writer reads them
    double draw_seconds = 0;
    size_t sampled = 0;  // samples already on the trails
    for (size_t f = 0; f < shapes.size(); ++f) {
      if (has_trails) extend_trails(trails, sampled, p, samples, frames, f);
      const auto before = std::chrono::steady_clock::now();
      render::Image image = renderer.draw(shapes[f], trails, view);
      draw_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
      const double t = samples.t[frames.samples[f]];
      if (one_colour(image)) ++empty_frames;
      drawn.push_back({{"file", fmt::format("frame_{:04d}.png", f)}, {"t", t}, {"hash", render::pixel_hash(image)}});
      queue.push(std::move(image));
    }
    queue.finish();
    // a 1-D PDE's space-time picture, in its own view
    if (const auto picture = space_time(p, samples, frames)) {
      const render::View whole = render::make_view(std::span(&*picture, 1), render::Look{}, width, height);
      write_file_atomic(out / "space_time.png", render::encode_png(renderer.draw(*picture, {}, whole)));
      std::lock_guard lock(summary_mutex);
      summary["space_time"] = "space_time.png";
    }
    const double span = samples.t[frames.samples.back()];
    const int fps = span > 0 ? std::clamp(static_cast<int>(std::lround((shapes.size() - 1) / span)), 1, 60) : 1;
    if (shapes.size() > 1 && movies && options.animations) encode_movies(out, fps);
    std::lock_guard lock(summary_mutex);
    summary["draw_seconds"] = draw_seconds;
    summary["fps"] = fps;
    summary["empty_frames"] = empty_frames;
  } catch (const gl::GlError& e) {
    throw InputError(e.what());
  } catch (const std::runtime_error& e) {
    throw InputError(e.what());
  }

  say_empty_frames(empty_frames, shapes.size(), width, height);
  // written outside summary_mutex: a file's temporary registers with the interruption's registry, whose lock the
  // cleaning thread holds while it runs the last words above, which take summary_mutex (the inverse order
  // deadlocked a SIGTERM'd `study pictures` for good, one try in a few hundred)
  std::string text;
  {
    std::lock_guard lock(summary_mutex);
    text = summary.dump(2) + "\n";
  }
  try {
    write_file_atomic(out / "render.json", text);
  } catch (const std::runtime_error& e) {
    throw InputError(e.what());
  }
  return {samples.result.status, samples.result.status == Status::ok ? "" : fmt::format("{}: {}", p.method, samples.result.message), samples.t.back()};
}

}  // namespace stepwise
