// `stepwise render`: a scene run through its method and drawn headlessly, frame by frame, to PNGs and,
// where ffmpeg is installed, an MP4 and a GIF.
#pragma once

#include "run_command.hpp"

#include <string>

namespace stepwise {

struct RenderOptions {
  RunOptions run;                  // the scene, --set, --method, --dt, --t-end as `stepwise run` takes them
  int frames = 60;                 // frames from t = 0 to the scene's t_end
  std::string size = "1280x720";   // WxH in pixels
  std::string backend = "osmesa";  // osmesa | egl
  std::string out;
};

// exit status: 0 drawn, 1 the run diverged or failed (the frames up to then drawn), 2 bad input or no context
int render_command(const RenderOptions& options);

}  // namespace stepwise
