// A scene run through its method and drawn headlessly, frame by frame, to PNGs and, where ffmpeg is
// installed, an MP4 and a GIF, with render.json beside them: what `stepwise render` does, and what the
// report's pictures call in its own process (each sweep thread makes its own GL context).
#pragma once

#include <stepwise/run/prepare.hpp>

#include <string>

namespace stepwise {

struct RenderOptions {
  RunOptions run;                  // the scene, --set, --method, --dt, --t-end as `stepwise run` takes them
  int frames = 60;                 // frames from t = 0 to the scene's t_end
  std::string size = "1280x720";   // WxH in pixels
  std::string backend = "osmesa";  // osmesa | egl
  std::string out;
  bool animations = true;          // the MP4 and GIF too, where ffmpeg is installed (else said on stderr)
};

// how the drawn run ended: ok, or diverged or failed at t_last with the message (the frames up to then drawn)
struct RenderedRun {
  Status status = Status::ok;
  std::string message;
  double t_last = 0;
};

// InputError, with the message `stepwise render` prints, for bad input, a context that cannot be made or
// frames that cannot be drawn or written (nothing is drawn for bad input)
RenderedRun render_scene(const RenderOptions& options);

// the checks render_scene makes of its inputs before it makes a GL context or runs anything (the options, the
// scene, the outputs, the frames' memory and disk); InputError as render_scene says it. What the fuzzer calls
void check_render(const RenderOptions& options);

}  // namespace stepwise
