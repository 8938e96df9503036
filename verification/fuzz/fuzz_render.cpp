// libFuzzer target: `stepwise render`'s options and scene file -> the checks render makes before it makes a GL
// context or runs anything (run/render_scene.hpp's check_render: the size, frames and backend as typed, the
// scene prepared as `run` takes it, the outputs, the frames' memory and disk). The input's first line is
// "SIZE FRAMES BACKEND" as a user types them (FRAMES a whole number, as the command line parses it), the rest
// is the scene file. Bad input must come back as InputError (exit 2); a crash, a sanitizer report, a hang or any
// other exception is a bug.
//   build/fuzz/verification/fuzz/fuzz_render -max_total_time=30 verification/fuzz/render_corpus
#include "fuzz_limits.hpp"
#include "run/render_scene.hpp"

#include <unistd.h>

#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

namespace {

// the scene as a file, where render reads it (removed at exit); the outputs in a directory that is never made
const std::string scene_file = "/tmp/fuzz_render_" + std::to_string(::getpid()) + ".toml";
const std::string out = "/tmp/fuzz_render_" + std::to_string(::getpid()) + ".out/never-made";

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  std::atexit([] { std::remove(scene_file.c_str()); });
  return stepwise::fuzz::limit_memory();
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace stepwise;
  if (size > stepwise::fuzz::largest_input) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto newline = text.find('\n');
  if (newline == std::string_view::npos) return 0;
  std::istringstream first{std::string(text.substr(0, newline))};
  std::string size_text, frames_text, backend;
  first >> size_text >> frames_text >> backend;
  RenderOptions options;
  options.size = size_text;
  options.backend = backend;
  const auto [end, parsed] = std::from_chars(frames_text.data(), frames_text.data() + frames_text.size(), options.frames);
  if (parsed != std::errc() || end != frames_text.data() + frames_text.size()) return 0;  // the command line refuses it first
  std::ofstream(scene_file, std::ios::binary | std::ios::trunc) << text.substr(newline + 1);
  options.run.scene_file = scene_file;
  options.out = out;
  try {
    check_render(options);
  } catch (const InputError&) {
  }
  return 0;
}
