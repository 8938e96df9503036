#include "render_command.hpp"

#include <iostream>

namespace stepwise {

int render_command(const RenderOptions& options) {
  try {
    const RenderedRun drawn = render_scene(options);
    if (drawn.status != Status::ok) {
      std::cerr << "stepwise render: " << drawn.message << " (frames drawn up to t = " << drawn.t_last << " s)\n";
      return 1;
    }
    return 0;
  } catch (const InputError& e) {
    std::cerr << "stepwise render: " << e.what() << '\n';
    return 2;
  }
}

}  // namespace stepwise
