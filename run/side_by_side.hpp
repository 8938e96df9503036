// One scene run by several methods and drawn side by side in one video: a grid of panels seen by one camera at
// the same simulated times, each labelled with its method, its CPU time and how far its picture is, in pixels,
// from the last panel's, the reference. What the report's "Side by side" section films.
#pragma once

#include <stepwise/run/prepare.hpp>

#include <string>
#include <tuple>
#include <vector>

namespace stepwise {

struct Panel {
  std::string method;
  double dt = 0;        // s: a fixed step dividing the frame interval
  std::string setting;  // how the label says the step ("dt 1/60 s")
  int substeps = 0;     // a position-based method's: its step in this many substeps of one iteration (0: not one)
  std::vector<std::string> sets;  // the panel's own scene overrides, key=value, after the scene's (its model's variant)
  int iterations = 0;   // vbd's: its sweeps a step (0: the method's default)
};

struct SideBySideOptions {
  RunOptions run;             // the scene, its --set and t_end (method and step: the panels')
  std::vector<Panel> panels;  // in reading order; the last is the reference the others are measured against
  int fps = 30;               // frames per second of simulated time, and of the video: it plays in real time
  int panel_width = 640, panel_height = 360, columns = 2;
  std::string video;          // the MP4 written (through a temporary name beside it)
};

struct FilmedPanel {
  std::string method, setting;
  double dt = 0;  // s
  Status status = Status::ok;
  std::string message;
  double t_last = 0;       // s: the last time the run reached (its frames after it show that state)
  double steps = 0;
  double cpu_seconds = 0;  // the run's thread CPU time, the frames' output included
  double pixel_error = 0;  // the largest pixel_distance from the reference over the frames it reached; NaN if it diverged
  std::string label;       // its two lines, " / " between them, as drawn
  static auto fields(auto& s) {
    return std::tie(s.method, s.setting, s.dt, s.status, s.message, s.t_last, s.steps, s.cpu_seconds, s.pixel_error, s.label);
  }
};

struct Filmed {
  std::vector<double> t;                     // the frames' simulated times
  std::vector<std::vector<double>> shown_t;  // frame -> panel -> the simulated time its panel shows
  std::vector<std::vector<double>> shown_error;  // frame -> panel -> its pixel_distance from the reference
  std::vector<FilmedPanel> panels;
  int width = 0, height = 0;
  static auto fields(auto& s) { return std::tie(s.t, s.shown_t, s.shown_error, s.panels, s.width, s.height); }
};

// InputError for options the scene or a method refuses (before anything is drawn); std::runtime_error naming
// the backend or ffmpeg if the GL context or the encoding fails. Needs ffmpeg with libx264 and drawtext
Filmed film_side_by_side(const SideBySideOptions& options);

// the thread CPU seconds of the run film_side_by_side makes for `panel` (outputs every frame) up to t_end: the
// least of as many repeats as fit in 20 ms (at most 100), for runs of microseconds; InputError as
// film_side_by_side says it
double panel_cpu_seconds(const RunOptions& run, const Panel& panel, int fps, double t_end);

// "CPU 0.41 s", "CPU 35 us": a CPU time as a label says it
std::string cpu_text(double seconds);

}  // namespace stepwise
