#include "side_by_side.hpp"

#include "render/renderer.hpp"
#include "run/measure.hpp"
#include "run/message.hpp"
#include "run/process.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace stepwise {
namespace {

namespace fs = std::filesystem;

// a panel's run: the state it shows at each frame (its last reached one after it stopped)
struct PanelRun {
  std::vector<Shapes> shapes;   // one a frame
  std::vector<double> shown_t;  // the time each frame's state is at
  size_t reached = 0;           // frames reached (the first `reached` are the run's own)
  RunResult result;
};

PanelRun run_panel(const PreparedRun& p, double interval, int frames) {
  PanelRun r;
  StateSamples s = sample_states(*p.model, p.method, p.control, interval * (frames - 1), interval);
  // the samples on the frames' times, in order; a diverged run's last output may fall between them
  for (size_t k = 0; k < s.t.size() && r.shapes.size() < static_cast<size_t>(frames); ++k) {
    const double t = interval * static_cast<double>(r.shapes.size());
    if (std::abs(s.t[k] - t) > 1e-9 * interval * frames || !s.y[k].allFinite()) break;
    r.shapes.push_back(*p.model->shapes(s.y[k]));
    r.shown_t.push_back(s.t[k]);
  }
  r.reached = r.shapes.size();
  while (r.shapes.size() < static_cast<size_t>(frames)) {
    r.shapes.push_back(r.shapes.back());
    r.shown_t.push_back(r.shown_t.back());
  }
  r.result = std::move(s.result);
  return r;
}

std::string pixels_text(double pixels) {
  return pixels >= 9.95 ? fmt::format("{:.0f} px", pixels) : pixels >= 0.095 ? fmt::format("{:.1f} px", pixels) : "under 0.1 px";
}

// what drawtext is given between quotes: nothing its option or filtergraph parsers read as syntax
void check_label(const std::string& text) {
  if (text.find_first_of("',:;[]\\%{}\n") != std::string::npos) throw std::logic_error(fmt::format("side by side: label '{}' has a character ffmpeg's filters parse", text));
}

// ffmpeg's filters on the composed frames: each panel's two label lines in a light box at its top left, and a
// line between the panels
std::string label_filters(const std::vector<FilmedPanel>& panels, const SideBySideOptions& o, int width, int height) {
  const int size = std::max(10, o.panel_height / 20), margin = size / 2;
  std::string chain;
  const auto add = [&](const std::string& filter) { chain += (chain.empty() ? "" : ",") + filter; };
  for (int c = 1; c < o.columns; ++c) add(fmt::format("drawbox=x={}:y=0:w=2:h={}:color=0x777777:t=fill", c * o.panel_width - 1, height));
  const int rows = (static_cast<int>(panels.size()) + o.columns - 1) / o.columns;
  for (int r = 1; r < rows; ++r) add(fmt::format("drawbox=x=0:y={}:w={}:h=2:color=0x777777:t=fill", r * o.panel_height - 1, width));
  for (size_t k = 0; k < panels.size(); ++k) {
    const int x = static_cast<int>(k) % o.columns * o.panel_width + margin, y = static_cast<int>(k) / o.columns * o.panel_height + margin;
    const std::string& label = panels[k].label;
    const size_t split = label.find(" / ");
    const std::string lines[2] = {label.substr(0, split), split == std::string::npos ? "" : label.substr(split + 3)};
    for (int line = 0; line < 2; ++line) {
      if (lines[line].empty()) continue;
      check_label(lines[line]);
      add(fmt::format("drawtext=font='DejaVu Sans':expansion=none:text='{}':x={}:y={}:fontsize={}:fontcolor=black:box=1:"
                      "boxcolor=white@0.8:boxborderw={}",
                      lines[line], x, y + line * (size + margin), size, margin / 2));
    }
  }
  return chain;
}

PreparedRun prepare_panel(const RunOptions& scene, const Panel& panel, double interval) {
  RunOptions run = scene;
  run.method = panel.method;
  run.dt = panel.dt;
  run.sets.insert(run.sets.end(), panel.sets.begin(), panel.sets.end());
  // a position-based panel's substeps of one iteration each; vbd's sweeps (GCC 12 warns, falsely, of an overflow in a
  // string assigned from a literal here: the values are made as strings first)
  if (panel.substeps > 0) {
    run.method_options.insert_or_assign("substeps", std::to_string(panel.substeps));
    run.method_options.insert_or_assign("iterations", std::to_string(1));
  }
  if (panel.iterations > 0) run.method_options.insert_or_assign("iterations", std::to_string(panel.iterations));
  PreparedRun p = prepare_run(run);
  const double steps = interval / panel.dt;
  if (!(std::abs(steps - std::round(steps)) <= 1e-9 * steps))
    throw InputError(fmt::format("side by side: {} at dt {} s takes {} steps a frame of {} s: not a whole number", panel.method, panel.dt, steps, interval));
  return p;
}

int frames_until(double t_end, double interval) { return 1 + static_cast<int>(std::floor(t_end / interval * (1 + 1e-12))); }

}  // namespace

double panel_cpu_seconds(const RunOptions& run, const Panel& panel, int fps, double t_end) {
  RunOptions until = run;
  until.t_end = t_end;
  const double interval = 1.0 / fps;
  const int frames = frames_until(t_end, interval);
  if (frames < 2) throw InputError(fmt::format("side by side: t_end {} s is shorter than a frame of 1/{} s", t_end, fps));
  double least = INFINITY, total = 0;
  for (int repeat = 0; repeat < 100 && total < 0.02; ++repeat) {
    PreparedRun p = prepare_panel(until, panel, interval);
    const PanelRun r = run_panel(p, interval, frames);
    if (r.result.status != Status::ok)
      throw InputError(fmt::format("side by side: {} at dt {} s: {}", panel.method, panel.dt, r.result.message));
    least = std::min(least, r.result.stats.cpu_seconds);
    total += r.result.stats.cpu_seconds;
  }
  return least;
}

std::string cpu_text(double seconds) {
  if (seconds >= 0.095) return fmt::format("CPU {:.2f} s", seconds);
  if (seconds >= 0.95e-3) return fmt::format("CPU {:.1f} ms", seconds * 1e3);
  return fmt::format("CPU {:.0f} us", seconds * 1e6);
}

Filmed film_side_by_side(const SideBySideOptions& o) {
  if (o.panels.size() < 2) throw InputError("side by side: a method and the reference at least");
  if (o.fps < 1 || o.panel_width < 16 || o.panel_height < 16 || o.columns < 1)
    throw InputError(fmt::format("side by side: {} frames a second of {} x {} panels, {} across: none to draw", o.fps, o.panel_width, o.panel_height,
                                 o.columns));
  const double interval = 1.0 / o.fps;
  std::vector<PreparedRun> prepared;
  for (const Panel& panel : o.panels) prepared.push_back(prepare_panel(o.run, panel, interval));
  const double t_end = prepared.back().t_end;
  const int frames = frames_until(t_end, interval);
  if (frames < 2) throw InputError(fmt::format("side by side: t_end {} s is shorter than a frame of 1/{} s", t_end, o.fps));

  std::vector<PanelRun> runs;
  for (auto& p : prepared) runs.push_back(run_panel(p, interval, frames));

  Filmed filmed;
  const int rows = (static_cast<int>(o.panels.size()) + o.columns - 1) / o.columns;
  filmed.width = o.columns * o.panel_width;
  filmed.height = rows * o.panel_height;
  // one camera for every panel: the reference's view of its whole run
  const render::View view = render::make_view(runs.back().shapes, prepared.back().scene.look, o.panel_width, o.panel_height);
  filmed.shown_t.assign(frames, {});
  filmed.shown_error.assign(frames, {});
  for (int f = 0; f < frames; ++f) {
    filmed.t.push_back(interval * f);
    for (const PanelRun& r : runs) {
      filmed.shown_t[f].push_back(r.shown_t[f]);
      filmed.shown_error[f].push_back(static_cast<size_t>(f) < r.reached
                                          ? render::pixel_distance(r.shapes[f], runs.back().shapes[f], view.camera, o.panel_width, o.panel_height)
                                          : NAN);
    }
  }
  for (size_t k = 0; k < runs.size(); ++k) {
    const RunResult& result = runs[k].result;
    FilmedPanel panel{o.panels[k].method, o.panels[k].setting, o.panels[k].dt, result.status, result.message, runs[k].shown_t[runs[k].reached - 1],
                      static_cast<double>(result.stats.steps), result.stats.cpu_seconds, 0, ""};
    // a run of microseconds timed again as panel_cpu_seconds times it, the least of repeats: what a budget is set by
    if (panel.cpu_seconds < 0.02 && result.status == Status::ok) panel.cpu_seconds = std::min(panel.cpu_seconds, panel_cpu_seconds(o.run, o.panels[k], o.fps, t_end));
    for (int f = 0; f < frames; ++f) panel.pixel_error = std::max(panel.pixel_error, filmed.shown_error[f][k]);
    const bool whole = result.status == Status::ok && runs[k].reached == static_cast<size_t>(frames);
    if (!whole) panel.pixel_error = NAN;
    const bool reference = k + 1 == runs.size();
    panel.label = fmt::format("{}  {}{} / {}{}", panel.method, panel.setting, reference ? "  (reference)" : "", cpu_text(panel.cpu_seconds),
                              !whole      ? fmt::format("   {} at t {:.2f} s", to_string(result.status), panel.t_last)
                              : reference ? std::string()
                                          : fmt::format("   off by {}", pixels_text(panel.pixel_error)));
    filmed.panels.push_back(std::move(panel));
  }

  // the frames drawn panel by panel into one picture, handed to ffmpeg raw as they are made
  const fs::path video(o.video), temporary = video.parent_path() / fmt::format(".{}.tmp", video.filename().string());
  std::unique_ptr<gl::Context> context;
  try {
    context = gl::make_context(gl::Backend::osmesa);
  } catch (const gl::GlError& e) {
    throw std::runtime_error(fmt::format("side by side: {}", e.what()));
  }
  render::Renderer renderer(*context, o.panel_width, o.panel_height);
  FedProcess ffmpeg({"ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgba", "-s", fmt::format("{}x{}", filmed.width, filmed.height),
                     "-framerate", std::to_string(o.fps), "-i", "-", "-vf", label_filters(filmed.panels, o, filmed.width, filmed.height), "-c:v",
                     "libx264", "-preset", "veryfast", "-crf", "20", "-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4", temporary.string()});
  render::Image frame{filmed.width, filmed.height, std::vector<std::uint8_t>(static_cast<size_t>(filmed.width) * filmed.height * 4, 0)};
  std::vector<std::vector<std::vector<Eigen::Vector3d>>> trails(runs.size());
  bool taken = true;
  for (int f = 0; f < frames && taken; ++f) {
    for (size_t k = 0; k < runs.size(); ++k) {
      const Shapes& shapes = runs[k].shapes[f];
      size_t trail = 0;
      for (const auto& ball : shapes.balls)
        if (ball.trail) {
          if (trails[k].size() <= trail) trails[k].emplace_back();
          trails[k][trail++].push_back(ball.center);
        }
      const render::Image panel = renderer.draw(shapes, trails[k], view);
      const size_t x0 = static_cast<size_t>(k % o.columns) * o.panel_width, y0 = static_cast<size_t>(k / o.columns) * o.panel_height;
      for (int y = 0; y < o.panel_height; ++y)
        std::copy_n(panel.rgba.begin() + static_cast<std::ptrdiff_t>(y) * o.panel_width * 4, o.panel_width * 4,
                    frame.rgba.begin() + static_cast<std::ptrdiff_t>(((y0 + y) * filmed.width + x0) * 4));
    }
    taken = ffmpeg.write(frame.rgba);
  }
  const int status = ffmpeg.finish();
  if (!taken || status != 0) {
    std::error_code ec;
    fs::remove(temporary, ec);
    throw std::runtime_error(fmt::format("side by side: ffmpeg (libx264, drawtext) failed making {}: exit status {}", video.string(), status));
  }
  fs::rename(temporary, video);
  return filmed;
}

}  // namespace stepwise
