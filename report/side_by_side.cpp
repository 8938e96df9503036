#include "side_by_side.hpp"

#include "studies.hpp"

#include "run/atomic_write.hpp"
#include "run/csv.hpp"
#include "run/measure.hpp"
#include "run/message.hpp"
#include "run/process.hpp"
#include "run/side_by_side.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <chrono>
#include <cmath>
#include <optional>

namespace stepwise {

namespace fs = std::filesystem;

namespace {

// a method of a clip and the step its calibration starts from (a position-based method's: the substep, its step
// being the frame)
struct Contender {
  const char* method;
  double dt;
};

// a clip: a scene, how long it runs, the CPU budget its methods share, and the reference
struct Clip {
  const char* scene;
  std::vector<std::string> sets;
  double t_end, quick_t_end;  // s
  // the budget: CPU seconds per simulated second where given, else what `anchor` costs at its step
  std::optional<double> per_second;
  Contender anchor;
  const char* budget_says;  // the budget in words
  double timed_share;       // of the run, that the methods are timed over (timed_span)
  std::vector<Contender> methods;
  Contender reference;      // converged: rk4 far below the steps the others take
  const char* says;         // what the clip shows
  double draw_ms;           // a panel's drawing at 640 x 360, measured: the expected cost
};

const std::vector<Clip>& clips() {
  static const std::vector<Clip> all{
      // the flag's methods at real time on one core (report/studies/cloth_realtime.cpp measures them there);
      // rk4 in place of tsitouras54, which is stability-bound here (1 s of CPU a simulated second at any loose
      // tolerance) and takes no fixed step for the frames to fall on
      {"flag", {}, 2.0, 0.5, 1.0, {"", 0}, "real time: 1 s of CPU per simulated second", 0.25,
       {{"implicit-euler", 1.0 / 60}, {"fast-mass-spring", 1.0 / 240}, {"rk4", 1e-3}, {"xpbd", 1.0 / 1200}}, {"rk4", 2.5e-4},
       "The seeds' 32 x 32 flag: the implicit methods take large steps and damp the billowing out; rk4 affords steps "
       "far below its stability limit; xpbd (its springs as compliant constraints) steps each frame in as many substeps "
       "as the budget buys.",
       5},
      // released at 170 degrees, near the top: a small energy error changes the swing's period, or sends it over
      {"pendulum", {"theta0=2.9670597283903604"}, 10.0, 5.0, std::nullopt, {"rk4", 1.0 / 30}, "rk4's CPU time at one step a frame", 1,
       {{"euler", 1e-2}, {"symplectic-euler", 1e-2}, {"rk4", 1.0 / 30}}, {"rk4", 1e-4},
       "The pendulum released at 170 degrees: explicit Euler gains energy, symplectic Euler keeps it but drifts in phase.", 2},
      // the seeds' scheme near its stability limit sets the budget: the method of lines, a few times dearer a step,
      // must take steps past its own limits there (implicit Euler, whose Newton matrix on this model is dense,
      // 8 192^2, cannot take a step within it)
      {"water-drop", {}, 3.0, 1.0, std::nullopt, {"wave-fd", 1.0 / 90}, "wave-fd's CPU time at 1/90 s, 0.79 of its stability limit (0.01415 s)", 1,
       {{"wave-fd", 5e-3}, {"symplectic-euler", 5e-3}, {"rk4", 5e-3}}, {"rk4", 1e-3},
       "The drop's ring on the 64 x 64 height field, with the caustic on the pool's floor, at the cost of the seeds' scheme.", 25},
  };
  return all;
}

// the step that puts `dt` on the frames: a whole number of steps a frame, at least one, none longer than dt
double on_frames(double dt, double interval) { return interval / std::max(1.0, std::ceil(interval / dt * (1 - 1e-12))); }

// the span the clip's methods are timed over: the whole run where it is cheap (a run's fixed costs, ~1 ms on the
// water, then count once as they will), else a quarter of it (the flag's runs take seconds, nearly all steps),
// a whole number of frames, at least four
double timed_span(const Clip& clip, double t_end, double interval) {
  return std::min(t_end, interval * std::max(4.0, std::floor(t_end * clip.timed_share / interval)));
}

std::string step_text(double dt) {
  const double per_second = 1 / dt;
  return std::abs(per_second - std::round(per_second)) < 1e-6 * per_second ? fmt::format("dt 1/{:.0f} s", per_second) : fmt::format("dt {:.3g} s", dt);
}

// `method` at n steps a frame of `interval`: n steps of interval / n, or a position-based method's one step a
// frame in n substeps (of one iteration: Macklin et al.'s small steps)
Panel panel_at(const char* method, int n, double interval) {
  if (find_method(method)->substepped) return {method, interval, fmt::format("{} in {} substeps", step_text(interval), n), n};
  return {method, interval / n, step_text(interval / n)};
}

// the steps a frame that keep `method`'s CPU time within `budget` over t_end, at least one: its CPU time over
// the span, c(n) = a + b n at n steps a frame (a: the run's fixed costs and outputs, b: the steps), measured at
// two step counts, scaled to the run and solved for the budget
int steps_within(const RunOptions& scene, const char* method, double dt, int fps, double t_end, double span, double budget) {
  const double interval = 1.0 / fps;
  const int n1 = static_cast<int>(std::lround(interval / on_frames(dt, interval))), n2 = 2 * n1;
  const auto cost = [&](int n) { return panel_cpu_seconds(scene, panel_at(method, n, interval), fps, span) * t_end / span; };
  const double c1 = cost(n1), c2 = cost(n2);
  const double b = std::max(c2 - c1, 1e-3 * c2) / (n2 - n1), a = std::max(0.0, c1 - b * n1);
  return static_cast<int>(std::clamp(std::floor((budget - a) / b), 1.0, 1e6));
}

struct Shot {
  Filmed filmed;
  double budget = 0;  // CPU seconds for the run
  static auto fields(auto& s) { return std::tie(s.filmed, s.budget); }
};

}  // namespace

std::string side_by_side_section(const fs::path& dir, const fs::path& scenes_dir, const StudyContext& ctx) {
  std::string md = "## Side by side\n\n";
  if (!on_path("ffmpeg")) {
    print_error("report", "ffmpeg is not installed: the side-by-side videos were skipped (apt-get install ffmpeg)");
    return md + "Not filmed: ffmpeg is not installed here (it encodes the videos and draws their labels).\n\n";
  }
  const int fps = ctx.quick ? 15 : 30;
  // the clips whose scene the scenes directory has (STEPWISE_SCENES may name another): the others said once, skipped
  std::vector<Clip> all;
  std::vector<std::string> missing;
  for (const Clip& clip : clips()) {
    if (fs::exists(scenes_dir / (std::string(clip.scene) + ".toml")))
      all.push_back(clip);
    else
      missing.push_back(clip.scene);
  }
  std::string skipped;
  if (!missing.empty()) {
    skipped = fmt::format("Not filmed, their scene files not being in {}: {}.", scenes_dir.string(), fmt::join(missing, ", "));
    print_error("report", fmt::format("side by side: {}", skipped));
    if (all.empty()) return md + skipped + "\n\n";
  }
  std::vector<std::string> labels;
  std::vector<double> costs;
  for (const Clip& clip : all) {
    labels.push_back(clip.scene);
    const double t_end = ctx.quick ? clip.quick_t_end : clip.t_end;
    // the runs at their budget, the reference's about as much again, and the frames drawn
    costs.push_back(1e9 * t_end * (clip.per_second.value_or(0.01) * 5) + 4 * fps * t_end * clip.draw_ms * 1e6);
  }
  if (ctx.progress) ctx.progress->begin_study("side-by-side");
  const auto start = std::chrono::steady_clock::now();
  fs::create_directories(dir / "side_by_side");
  const auto shots = ctx.sweep<Shot>(labels, [&](size_t i) {
    const Clip& clip = all[i];
    SideBySideOptions o;
    o.run.scene_file = (scenes_dir / (std::string(clip.scene) + ".toml")).string();
    o.run.sets = clip.sets;
    o.run.t_end = ctx.quick ? clip.quick_t_end : clip.t_end;
    o.fps = fps;
    o.video = (dir / "side_by_side" / (std::string(clip.scene) + ".mp4")).string();
    const double interval = 1.0 / fps, t_end = *o.run.t_end;
    // each method's step at the budget (steps_within)
    Shot shot;
    const double span = timed_span(clip, t_end, interval);
    shot.budget = clip.per_second ? *clip.per_second * t_end
                                  : panel_cpu_seconds(o.run, {clip.anchor.method, on_frames(clip.anchor.dt, interval), ""}, fps, span) * t_end / span;
    for (const Contender& c : clip.methods) {
      // the method that sets the budget takes its own step
      const bool anchor = c.method == std::string_view(clip.anchor.method);
      const int n = anchor ? static_cast<int>(std::lround(interval / on_frames(clip.anchor.dt, interval)))
                           : steps_within(o.run, c.method, c.dt, fps, t_end, span, shot.budget);
      o.panels.push_back(panel_at(c.method, n, interval));
    }
    const double reference_dt = on_frames(clip.reference.dt, interval);
    o.panels.push_back({clip.reference.method, reference_dt, step_text(reference_dt)});
    try {
      shot.filmed = film_side_by_side(o);
    } catch (const InputError& e) {  // a shipped scene the clip's plan does not fit: ours to fix
      throw std::runtime_error(fmt::format("side by side {}: {}", clip.scene, e.what()));
    }
    return shot;
  }, costs);
  if (ctx.progress) ctx.progress->end_study(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());

  Table panels{{"scene", "panel", "method", "setting", "dt", "steps", "cpu_seconds", "budget_cpu_seconds", "cpu_over_budget", "pixel_error", "status",
                "t_last", "label", "video", "frames", "width", "height", "fps"},
               {}};
  Table frames{{"scene", "frame", "t", "panel", "method", "shown_t", "pixel_error"}, {}};
  std::string body;
  for (size_t i = 0; i < all.size(); ++i) {
    const Clip& clip = all[i];
    const Shot& shot = shots[i];
    const Filmed& f = shot.filmed;
    const std::string video = fmt::format("side_by_side/{}.mp4", clip.scene);
    const size_t first = panels.rows.size();
    for (size_t k = 0; k < f.panels.size(); ++k) {
      const FilmedPanel& p = f.panels[k];
      const bool reference = k + 1 == f.panels.size();
      panels.rows.push_back({std::string(clip.scene), static_cast<long>(k), p.method, p.setting, p.dt, p.steps, p.cpu_seconds,
                             reference ? NAN : shot.budget, reference ? NAN : p.cpu_seconds / shot.budget, p.pixel_error,
                             std::string(to_string(p.status)), p.t_last, p.label, video, static_cast<long>(f.t.size()), static_cast<long>(f.width),
                             static_cast<long>(f.height), static_cast<long>(fps)});
    }
    for (size_t n = 0; n < f.t.size(); ++n)
      for (size_t k = 0; k < f.panels.size(); ++k)
        frames.rows.push_back({std::string(clip.scene), static_cast<long>(n), f.t[n], static_cast<long>(k), f.panels[k].method, f.shown_t[n][k],
                               f.shown_error[n][k]});
    double low = INFINITY, high = 0;
    for (size_t k = first; k + 1 < panels.rows.size(); ++k) {
      low = std::min(low, std::get<double>(cell_of(panels, panels.rows[k], "cpu_over_budget")));
      high = std::max(high, std::get<double>(cell_of(panels, panels.rows[k], "cpu_over_budget")));
    }
    body += fmt::format("### {}\n\n{} The budget: {}, {} here; each method's step is the longest whole fraction of a frame (xpbd's: the most substeps of a frame) that its "
                        "CPU time, measured at two steps beforehand, keeps within it (at least one step a frame). Filmed, they took "
                        "{:.2f} to {:.2f} of the budget (whole steps a frame, and CPU times that vary from run to run). The last panel "
                        "is the reference.\n\n",
                        clip.scene, clip.says, clip.budget_says, cpu_text(shot.budget), low, high);
    body += fmt::format("<video controls loop muted playsinline preload=\"metadata\" width=\"{}\" style=\"max-width: 100%; height: auto\" src=\"{}\"></video>\n\n"
                        "[{}]({}) ({} x {}, {} frames at {} a second: it plays in real time)\n\n",
                        f.width, video, video, video, f.width, f.height, f.t.size(), fps);
    body += markdown_table(panels, {{"method", "method"},
                                    {"setting", "step"},
                                    {"cpu_seconds", "CPU s", shown_as("{:.3g}")},
                                    {"cpu_over_budget", "of the budget", shown_as("{:.2f}")},
                                    {"pixel_error", "largest offset (px)", shown_as("{:.3g}")},
                                    {"status", "status"}},
                           [&](size_t row) { return row >= first; });
    body += "\n";
  }
  write_file_atomic(dir / "side_by_side.csv", to_csv(panels));
  write_file_atomic(dir / "side_by_side_frames.csv", to_csv(frames));
  md += fmt::format("The flag, the 170-degree pendulum and the water drop, each run by three methods at one CPU budget and filmed beside a converged reference, seen by one camera "
                    "at the same simulated times: each panel is labelled with its method and step, its CPU time, and its largest offset "
                    "from the reference over the run, in pixels of its {} x {} panel (the farthest any drawn point lies from the same point "
                    "of the reference's picture). Data: [side_by_side.csv](side_by_side.csv), "
                    "[side_by_side_frames.csv](side_by_side_frames.csv).{}\n\n",
                    640, 360, skipped.empty() ? "" : " " + skipped);
  return md + body;
}

}  // namespace stepwise
