#include "side_by_side.hpp"

#include "studies.hpp"

#include "run/atomic_write.hpp"
#include "run/csv.hpp"
#include "run/measure.hpp"
#include "run/message.hpp"
#include "run/process.hpp"
#include "run/side_by_side.hpp"
#include "verification/continuum_checks.hpp"

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
  bool continuum = false;  // on a cloth: the continuum of the springs' own measured material, not the springs
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
  const char* name = nullptr;  // the clip's name (its video's), where one scene has two clips; else the scene's
  std::string clip() const { return name ? name : scene; }
  bool two_models() const {
    return reference.continuum || std::any_of(methods.begin(), methods.end(), [](const Contender& c) { return c.continuum; });
  }
};

const std::vector<Clip>& clips() {
  static const std::vector<Clip> all{
      // the flag's methods at real time on one core (report/studies/cloth_realtime.cpp measures them there);
      // rk4 in place of tsitouras54, which is stability-bound here (1 s of CPU a simulated second at any loose
      // tolerance) and takes no fixed step for the frames to fall on
      {"flag", {}, 2.0, 0.5, 1.0, {"", 0}, "real time: 1 s of CPU per simulated second", 0.25,
       {{"implicit-euler", 1.0 / 60}, {"fast-mass-spring", 1.0 / 240}, {"rk4", 1e-3}, {"xpbd", 1.0 / 1200}, {"vbd", 1.0 / 60}}, {"rk4", 2.5e-4},
       "The seeds' 32 x 32 flag: the implicit methods take large steps and damp the billowing out; rk4 affords steps "
       "far below its stability limit; xpbd (its springs as compliant constraints) steps each frame in as many substeps "
       "as the budget buys, and vbd takes one step a frame in as many sweeps as it buys.",
       5},
      // the two cloths of the second seed at one budget, implicit Euler's on the spring flag at 1/60 s: the springs,
      // and the continuum of the springs' own material (the continuum-cloth study's), against the continuum converged
      {"flag", {}, 2.0, 0.5, std::nullopt, {"implicit-euler", 1.0 / 60}, "implicit Euler's CPU time on the spring flag at dt 1/60 s", 0.25,
       {{"implicit-euler", 1.0 / 60}, {"implicit-euler", 1.0 / 60, true}, {"symplectic-euler", 5e-4, true}}, {"rk4", 2.5e-4, true},
       "The seeds' two cloths at one CPU budget: the 32 x 32 spring flag and the continuum (finite elements) of the springs' "
       "own measured material by implicit Euler, and the continuum by symplectic Euler at the step the budget buys (its "
       "stability limit falls as the sheet stretches), against the continuum converged (the continuum-cloth study measures "
       "the same runs in a 720-pixel frame).",
       5, "flag-continuum"},
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

// the one clip a quick report films (a preview: the cheapest, whose point, a method's energy error in the swing,
// is the section's), the full report all of them
constexpr std::string_view quick_clip = "pendulum";

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

// the models of a clip's panels: on a clip of two (the spring cloth and the continuum), each panel's setting names
// its model, and a continuum panel runs with the material's sets
struct ClipModels {
  bool named = false;
  std::vector<std::string> continuum_sets;
};

// contender `c` at n steps a frame of `interval`: n steps of interval / n, or a position-based method's one step a
// frame in n substeps (of one iteration: Macklin et al.'s small steps), or vbd's one step a frame in n sweeps
Panel panel_at(const Contender& c, int n, double interval, const ClipModels& models) {
  const Method& method = *find_method(c.method);
  Panel panel = method.family == Family::vertex_block_descent
                    ? Panel{c.method, interval, fmt::format("{} in {} sweeps", step_text(interval), n), 0, {}, n}
                : method.option("substeps") ? Panel{c.method, interval, fmt::format("{} in {} substeps", step_text(interval), n), n}
                                    : Panel{c.method, interval / n, step_text(interval / n)};
  if (models.named) panel.setting = fmt::format("{}  {}", c.continuum ? "continuum" : "springs", panel.setting);
  if (c.continuum) panel.sets = models.continuum_sets;
  return panel;
}

// the steps a frame that keep contender `c`'s CPU time within `budget` over t_end, at least one: its CPU time over
// the span, c(n) = a + b n at n steps a frame (a: the run's fixed costs and outputs, b: the steps), measured at
// two step counts, scaled to the run and solved for the budget
int steps_within(const RunOptions& scene, const Contender& c, const ClipModels& models, int fps, double t_end, double span, double budget) {
  const double interval = 1.0 / fps;
  const int n1 = static_cast<int>(std::lround(interval / on_frames(c.dt, interval))), n2 = 2 * n1;
  const auto cost = [&](int n) { return panel_cpu_seconds(scene, panel_at(c, n, interval, models), fps, span) * t_end / span; };
  const double c1 = cost(n1), c2 = cost(n2);
  const double b = std::max(c2 - c1, 1e-3 * c2) / (n2 - n1), a = std::max(0.0, c1 - b * n1);
  return static_cast<int>(std::clamp(std::floor((budget - a) / b), 1.0, 1e6));
}

// the continuum cloth of the spring flag's own material, measured as the continuum-cloth study measures it, as sets
std::vector<std::string> springs_material_sets() {
  const Params material = continuum_of(uniaxial_stretch({{"continuum", 0}}, material_strip_rows, material_strip_strain));
  std::vector<std::string> sets;
  for (const auto& [key, value] : material) sets.push_back(fmt::format("{}={:.17g}", key, value));
  return sets;
}

struct Shot {
  Filmed filmed;
  double budget = 0;  // CPU seconds for the run
  static auto fields(auto& s) { return std::tie(s.filmed, s.budget); }
};

// the clips a report films (a quick one, quick_clip alone) whose scene the scenes directory has (STEPWISE_SCENES
// may name another); the others' names in `missing`
std::vector<Clip> clips_to_film(const fs::path& scenes_dir, bool quick, std::vector<std::string>& missing) {
  std::vector<Clip> all;
  for (const Clip& clip : clips()) {
    if (quick && clip.clip() != quick_clip) continue;
    if (fs::exists(scenes_dir / (std::string(clip.scene) + ".toml")))
      all.push_back(clip);
    else
      missing.push_back(clip.clip());
  }
  return all;
}

StudyOutput side_by_side(const StudyContext& ctx) {
  const fs::path& dir = ctx.out;
  const fs::path& scenes_dir = ctx.scenes_dir;
  StudyOutput out;
  if (!on_path("ffmpeg")) {
    print_error("report", "ffmpeg is not installed: the side-by-side videos were skipped (apt-get install ffmpeg)");
    out.markdown = "Not filmed: ffmpeg is not installed here (it encodes the videos and draws their labels).\n\n";
    return out;
  }
  const int fps = ctx.quick ? 15 : 30;
  std::vector<std::string> missing;
  const std::vector<Clip> all = clips_to_film(scenes_dir, ctx.quick, missing);
  std::string skipped;
  if (!missing.empty()) {
    skipped = fmt::format("Not filmed, their scene files not being in {}: {}.", scenes_dir.string(), fmt::join(missing, ", "));
    print_error("report", fmt::format("side by side: {}", skipped));
    if (all.empty()) {
      out.markdown = skipped + "\n\n";
      return out;
    }
  }
  std::vector<std::string> labels;
  std::vector<double> costs;
  for (const Clip& clip : all) {
    labels.push_back(clip.clip());
    const double t_end = ctx.quick ? clip.quick_t_end : clip.t_end;
    // the runs at their budget, the reference's about as much again, and the frames drawn
    costs.push_back(1e9 * t_end * (clip.per_second.value_or(0.01) * 5) + 4 * fps * t_end * clip.draw_ms * 1e6);
  }
  fs::create_directories(dir / "side_by_side");
  const auto shots = ctx.sweep<Shot>(labels, [&](size_t i) {
    const Clip& clip = all[i];
    SideBySideOptions o;
    o.run.scene_file = (scenes_dir / (std::string(clip.scene) + ".toml")).string();
    o.run.sets = clip.sets;
    o.run.t_end = ctx.quick ? clip.quick_t_end : clip.t_end;
    o.fps = fps;
    o.video = (dir / "side_by_side" / (clip.clip() + ".mp4")).string();
    const double interval = 1.0 / fps, t_end = *o.run.t_end;
    // each method's step at the budget (steps_within)
    Shot shot;
    const double span = timed_span(clip, t_end, interval);
    const ClipModels models{clip.two_models(), clip.two_models() ? springs_material_sets() : std::vector<std::string>{}};
    const int anchor_steps = static_cast<int>(std::lround(interval / on_frames(clip.anchor.dt, interval)));
    shot.budget = clip.per_second ? *clip.per_second * t_end : panel_cpu_seconds(o.run, panel_at(clip.anchor, anchor_steps, interval, models), fps, span) * t_end / span;
    for (const Contender& c : clip.methods) {
      // the contender that sets the budget takes its own step
      const bool anchor = c.method == std::string_view(clip.anchor.method) && c.continuum == clip.anchor.continuum;
      const int n = anchor ? anchor_steps : steps_within(o.run, c, models, fps, t_end, span, shot.budget);
      o.panels.push_back(panel_at(c, n, interval, models));
    }
    const int reference_steps = static_cast<int>(std::lround(interval / on_frames(clip.reference.dt, interval)));
    o.panels.push_back(panel_at(clip.reference, reference_steps, interval, models));
    try {
      shot.filmed = film_side_by_side(o);
    } catch (const InputError& e) {  // a shipped scene the clip's plan does not fit: ours to fix
      throw std::runtime_error(fmt::format("side by side {}: {}", clip.clip(), e.what()));
    }
    return shot;
  }, costs);

  Table panels{{"clip", "scene", "panel", "method", "setting", "dt", "steps", "cpu_seconds", "budget_cpu_seconds", "cpu_over_budget", "pixel_error", "status",
                "t_last", "label", "video", "frames", "width", "height", "fps"},
               {}};
  Table frames{{"clip", "scene", "frame", "t", "panel", "method", "shown_t", "pixel_error"}, {}};
  std::string body;
  for (size_t i = 0; i < all.size(); ++i) {
    const Clip& clip = all[i];
    const Shot& shot = shots[i];
    const Filmed& f = shot.filmed;
    const std::string video = fmt::format("side_by_side/{}.mp4", clip.clip());
    const size_t first = panels.rows.size();
    for (size_t k = 0; k < f.panels.size(); ++k) {
      const FilmedPanel& p = f.panels[k];
      const bool reference = k + 1 == f.panels.size();
      panels.rows.push_back({clip.clip(), std::string(clip.scene), static_cast<long>(k), p.method, p.setting, p.dt, p.steps, p.cpu_seconds,
                             reference ? NAN : shot.budget, reference ? NAN : p.cpu_seconds / shot.budget, p.pixel_error,
                             std::string(to_string(p.status)), p.t_last, p.label, video, static_cast<long>(f.t.size()), static_cast<long>(f.width),
                             static_cast<long>(f.height), static_cast<long>(fps)});
    }
    for (size_t n = 0; n < f.t.size(); ++n)
      for (size_t k = 0; k < f.panels.size(); ++k)
        frames.rows.push_back({clip.clip(), std::string(clip.scene), static_cast<long>(n), f.t[n], static_cast<long>(k), f.panels[k].method, f.shown_t[n][k],
                               f.shown_error[n][k]});
    double low = INFINITY, high = 0;
    for (size_t k = first; k + 1 < panels.rows.size(); ++k) {
      low = std::min(low, std::get<double>(cell_of(panels, panels.rows[k], "cpu_over_budget")));
      high = std::max(high, std::get<double>(cell_of(panels, panels.rows[k], "cpu_over_budget")));
    }
    body += fmt::format("### {}\n\n{} The budget: {}, {} here; each method's step is the longest whole fraction of a frame (xpbd's: the most substeps of a frame; vbd's: the most sweeps of its one step a frame) that its "
                        "CPU time, measured at two steps beforehand, keeps within it (at least one step a frame). Filmed, they took "
                        "{:.2f} to {:.2f} of the budget (whole steps a frame, and CPU times that vary from run to run). The last panel "
                        "is the reference.\n\n",
                        clip.clip(), clip.says, clip.budget_says, cpu_text(shot.budget), low, high);
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
  out.markdown = fmt::format("{}, each run at one CPU budget and filmed beside a converged reference, seen by one camera "
                    "at the same simulated times: each panel is labelled with its method and step, its CPU time, and its largest offset "
                    "from the reference over the run, in pixels of its {} x {} panel (the farthest any drawn point lies from the same point "
                    "of the reference's picture).{}\n\n",
                    ctx.quick ? "The 170-degree pendulum (the quick report's one clip; the full report films the flag by four methods, and as springs "
                                "and as the continuum, and the water drop beside it)"
                              : "The flag (by four methods, and as springs and as the continuum), the 170-degree pendulum and the water drop",
                    640, 360, skipped.empty() ? "" : " " + skipped) + body;
  out.tables = {{"side_by_side", std::move(panels)}, {"side_by_side_frames", std::move(frames)}};
  return out;
}

}  // namespace

Study side_by_side_study() {
  return {.name = "side-by-side", .title = "Side by side: the methods in motion at one CPU budget, in videos", .run = side_by_side, .drawn = true};
}

}  // namespace stepwise
