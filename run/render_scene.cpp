#include "render_scene.hpp"

#include "render/renderer.hpp"
#include "run/atomic_write.hpp"
#include "run/measure.hpp"
#include "run/process.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>

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

Samples simulate(PreparedRun& p, int frames, bool trails) {
  const size_t stride = trails ? 16 : 1;
  double interval = (frames > 1 ? p.t_end / (frames - 1) : p.t_end) / static_cast<double>(stride);
  // whole steps, rounded down so that the frames asked for fit before t_end
  if (p.control.dt) interval = std::max(1.0, std::floor(interval / *p.control.dt * (1 + 1e-9))) * *p.control.dt;
  const double frame_interval = interval * static_cast<double>(stride);
  const int count = frames > 1 ? std::min(frames, 1 + static_cast<int>(std::floor(p.t_end / frame_interval * (1 + 1e-12)))) : 1;
  Samples s;
  s.stride = stride;
  s.t.push_back(0);
  s.y.push_back(p.model->initial_state());
  if (count == 1) return s;
  p.control.observe = [](const Eigen::VectorXd& y) { return y; };
  Measured m = run_and_measure(*p.model, p.method, p.control, frame_interval * (count - 1), interval);
  for (size_t k = 0; k < m.result.trajectory.t.size(); ++k) {
    s.t.push_back(m.result.trajectory.t[k]);
    s.y.push_back(std::move(m.result.trajectory.y[k]));
  }
  s.result = std::move(m.result);
  return s;
}

// ffmpeg's MP4 (H.264, even sides) and GIF (480 px wide, its own palette) from the PNGs, each written to a
// temporary name and renamed
void encode_movies(const fs::path& dir, int fps) {
  if (!on_path("ffmpeg")) {
    std::cerr << "stepwise render: ffmpeg is not installed: wrote the PNG frames only (apt-get install ffmpeg for animation.mp4 "
                 "and animation.gif)\n";
    return;
  }
  const std::string input = (dir / "frame_%04d.png").string(), rate = std::to_string(fps);
  const std::vector<std::pair<std::string, std::vector<std::string>>> movies{
      {"animation.mp4", {"-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-f", "mp4"}},
      {"animation.gif", {"-vf", "scale=480:-1:flags=lanczos,split[a][b];[a]palettegen[p];[b][p]paletteuse", "-f", "gif"}}};
  for (const auto& [name, options] : movies) {
    const fs::path target = dir / name, temporary = dir / ("." + name + ".tmp");
    std::vector<std::string> args{"ffmpeg", "-y", "-loglevel", "error", "-framerate", rate, "-i", input};
    args.insert(args.end(), options.begin(), options.end());
    args.push_back(temporary.string());
    std::string why;
    const auto status = run_process(args, &why);
    if (!status || *status != 0) {
      fs::remove(temporary);
      throw std::runtime_error(fmt::format("ffmpeg ({}) failed: {}", name, status ? fmt::format("exit status {}", *status) : why));
    }
    fs::rename(temporary, target);
  }
}

}  // namespace

RenderedRun render_scene(const RenderOptions& options) {
  PreparedRun p;
  std::pair<int, int> size;
  gl::Backend backend{};
  try {
    size = parse_size(options.size);
    const auto parsed = gl::parse_backend(options.backend);
    if (!parsed) throw InputError(fmt::format("--backend {}: unknown backend (osmesa or egl)", options.backend));
    backend = *parsed;
    if (options.frames < 1 || options.frames > 100000) throw InputError(fmt::format("--frames {}: must lie in 1..100000", options.frames));
    p = prepare_run(options.run);
    if (!p.model->shapes(p.model->initial_state()))
      throw InputError(fmt::format("{}: model {} has nothing to draw", p.scene.where("model"), p.scene.model));
    ensure_writable_directory(options.out);
  } catch (const InputError&) {
    throw;
  } catch (const BadMethod& e) {
    throw InputError(fmt::format("{}: {}", p.scene.where("run.method"), e.what()));
  } catch (const std::runtime_error& e) {
    throw InputError(fmt::format("--out: {}", e.what()));
  }

  std::unique_ptr<gl::Context> context;
  try {
    context = gl::make_context(backend);
  } catch (const gl::GlError& e) {
    throw InputError(fmt::format("--backend {}: {}", options.backend, e.what()));
  }

  const auto [width, height] = size;
  const fs::path out(options.out);
  const auto start = std::chrono::steady_clock::now();
  const Shapes first = *p.model->shapes(p.model->initial_state());
  const bool has_trails = std::any_of(first.balls.begin(), first.balls.end(), [](const Shapes::Ball& b) { return b.trail; });
  Samples samples = simulate(p, options.frames, has_trails);
  const double simulate_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // the frames: every stride-th sample, and the last one if the run stopped between frames (diverged)
  std::vector<Shapes> shapes;
  std::vector<size_t> frame_samples;
  for (size_t k = 0; k < samples.y.size(); ++k)
    if (k % samples.stride == 0 || k + 1 == samples.y.size()) frame_samples.push_back(k);
  for (const size_t k : frame_samples) shapes.push_back(*p.model->shapes(samples.y[k]));
  // one view for the whole animation: the union of the frames' bounds
  const render::View view = render::make_view(shapes, p.scene.look, width, height);

  nlohmann::json summary;
  try {
    render::Renderer renderer(*context, width, height);
    render::EncodeQueue queue([&](size_t k, const std::string& png) { write_file_atomic(out / fmt::format("frame_{:04d}.png", k), png); });
    std::vector<std::vector<Eigen::Vector3d>> trails;
    summary["frames"] = nlohmann::json::array();
    double draw_seconds = 0;
    size_t sampled = 0;  // samples already on the trails
    for (size_t f = 0; f < shapes.size(); ++f) {
      for (; has_trails && sampled <= frame_samples[f]; ++sampled) {
        const Shapes at = sampled == frame_samples[f] ? shapes[f] : *p.model->shapes(samples.y[sampled]);
        size_t trail = 0;
        for (const auto& ball : at.balls)
          if (ball.trail) {
            if (trails.size() <= trail) trails.emplace_back();
            trails[trail++].push_back(ball.center);
          }
      }
      const auto before = std::chrono::steady_clock::now();
      render::Image image = renderer.draw(shapes[f], trails, view);
      draw_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
      const double t = samples.t[frame_samples[f]];
      summary["frames"].push_back({{"file", fmt::format("frame_{:04d}.png", f)}, {"t", t}, {"hash", render::pixel_hash(image)}});
      queue.push(std::move(image));
    }
    queue.finish();
    summary["draw_seconds"] = draw_seconds;
    const double span = samples.t[frame_samples.back()];
    const int fps = span > 0 ? std::clamp(static_cast<int>(std::lround((shapes.size() - 1) / span)), 1, 60) : 1;
    if (shapes.size() > 1) encode_movies(out, fps);
    summary["fps"] = fps;
  } catch (const gl::GlError& e) {
    throw InputError(e.what());
  } catch (const std::runtime_error& e) {
    throw InputError(e.what());
  }

  summary["scene"] = p.scene.name;
  summary["model"] = std::string(p.model->name());
  summary["method"] = p.method;
  summary["status"] = std::string(to_string(samples.result.status));
  summary["message"] = samples.result.message.empty() ? nlohmann::json(nullptr) : nlohmann::json(samples.result.message);
  summary["width"] = width;
  summary["height"] = height;
  summary["backend"] = options.backend;
  summary["renderer"] = context->description();
  summary["simulate_seconds"] = simulate_seconds;
  summary["camera"] = {{"eye", {view.camera.eye.x(), view.camera.eye.y(), view.camera.eye.z()}},
                       {"target", {view.camera.target.x(), view.camera.target.y(), view.camera.target.z()}},
                       {"up", {view.camera.up.x(), view.camera.up.y(), view.camera.up.z()}},
                       {"fov_deg", view.camera.fov_deg}};
  try {
    write_file_atomic(out / "render.json", summary.dump(2) + "\n");
  } catch (const std::runtime_error& e) {
    throw InputError(e.what());
  }
  return {samples.result.status, samples.result.status == Status::ok ? "" : fmt::format("{}: {}", p.method, samples.result.message), samples.t.back()};
}

}  // namespace stepwise
