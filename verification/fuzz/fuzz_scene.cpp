// libFuzzer target: a scene file's text -> its parameters -> the model -> a few steps of the scene's method,
// the path every `stepwise run` takes (run/prepare.hpp). Bad input must come back as InputError or BadMethod
// (the command line's exit 2), equations scenes included (seeded with the shipped ones); a crash, a sanitizer report, a hang or any other exception is a bug.
//   cmake --preset fuzz && cmake --build --preset fuzz
//   build/fuzz/verification/fuzz/fuzz_scene -max_total_time=60 verification/fuzz/corpus
#include "fuzz_limits.hpp"
#include "run/measure.hpp"
#include "run/prepare.hpp"
#include "solvers/method_table.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <stdlib.h>
#include <string_view>

// an equations scene is evaluated by the interpreter here: a compiler started for every new formula would take
// a tenth of a second an input (the compiled path is test_equations'), and its objects would fill a cache
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  ::setenv("STEPWISE_CC", "/nonexistent/stepwise-fuzz-uses-the-interpreter", 1);
  ::setenv("STEPWISE_CACHE", "/tmp/stepwise-fuzz-cache", 1);
  return stepwise::fuzz::limit_memory();
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace stepwise;
  if (size > stepwise::fuzz::largest_input) return 0;
  try {
    Scene scene = load_scene_text(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.toml");
    PreparedRun p = prepare_run(RunOptions{}, std::move(scene));
    // a GPU method needs a GL context (its own tests draw through llvmpipe), and a large grid is slow, not wrong
    if (find_method(p.method)->family == Family::gpu || p.model->size() > 20000) return 0;
    StepControl control = p.control;
    control.max_steps = 200;
    const double t_end = control.dt ? std::min(p.t_end, 20 * *control.dt) : std::min(p.t_end, 0.05);
    run_and_measure(*p.model, p.method, control, t_end, t_end / 4);
  } catch (const InputError&) {
  } catch (const BadMethod&) {
  }
  return 0;
}
