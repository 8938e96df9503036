#include "render_command.hpp"

#include "run/message.hpp"
#include "run/ranks.hpp"

#include <fmt/format.h>

namespace stepwise {

int render_command(const RenderOptions& options) {
  if (ranks::idle_here("render", "drawing is not split among ranks")) return 0;  // under mpirun, rank 0 draws
  try {
    const RenderedRun drawn = render_scene(options);
    if (drawn.status != Status::ok) {
      print_error("render", fmt::format("{} (frames drawn up to t = {} s)", drawn.message, drawn.t_last));
      return 1;
    }
    return 0;
  } catch (const InputError& e) {
    print_error("render", e.what());
    return 2;
  }
}

}  // namespace stepwise
