// `stepwise render`: a scene run through its method and drawn headlessly, frame by frame, to PNGs and,
// where ffmpeg is installed, an MP4 and a GIF.
#pragma once

#include "run/render_scene.hpp"

namespace stepwise {

// exit status: 0 drawn, 1 the run diverged or failed (the frames up to then drawn), 2 bad input or no context
int render_command(const RenderOptions& options);

}  // namespace stepwise
