// What the GPU shader methods share: a grid's state, four floats a cell, in two sets of planes, stepped by a
// pass that reads one set and writes the other, then swaps (ping-pong), on the GL context of gl/ (OSMesa's
// llvmpipe, or a GPU through EGL), which render/ uses too. Two kinds of pass compute the same cells with the
// same operations: the seeds' full-screen fragment pass over RGBA32F textures (gpu-wave, gpu-symplectic-euler,
// gpu-cloth), and a compute pass over shader storage buffers in 16 x 16 work groups (the -compute methods:
// OpenGL 4.3), which a data-centre GPU runs on all its units where it gives fragment passes only a few. They are solvers:
// they step model state, so they live here and not in render/. gpu_wave.cpp and gpu_cloth.cpp have the
// passes and register their methods; this file also has the device questions a run asks before it starts.
#pragma once

#include "gl/context.hpp"
#include <stepwise/solvers/fixed_step.hpp>
#include <stepwise/solvers/method.hpp>

#include <string>
#include <vector>

namespace stepwise::gpu {

using gl::Context;
using gl::Gl;

// which kind of pass steps a grid
enum class Pass { fragment, compute };
// a compute pass's work group: tile x tile cells, each an invocation
inline constexpr int tile = 16;
// what a compute pass's GLSL opens with: the version, the work group's size, and the grid's (`size`, which
// GpuGrid sets, as grid_size())
std::string compute_prelude();

// a width x height grid's state in `planes` planes, twice over, stepped by a pass from one set into the other;
// cell (x, y) is the grid's row y, column x (the CPU grids' row-major cell y * width + x). A fragment pass's
// planes are RGBA32F textures (plane p bound to texture unit p, written to colour attachment p); a compute
// pass's are storage buffers of vec4s (the set read bound to bindings 0.., the set written to 4..), its
// program given `size` (ivec2) and dispatched in work groups of tile x tile. `source`: the pass's GLSL
class GpuGrid {
 public:
  // GlError naming the limit where the grid passes GL_MAX_TEXTURE_SIZE (a fragment pass) or
  // GL_MAX_SHADER_STORAGE_BLOCK_SIZE (a compute pass), where the context cannot render to RGBA32F, or where it
  // has no compute shaders
  // `steps_per_dispatch` > 1: a compute pass takes up to that many steps a dispatch, told how many by its
  // uniform int `pass_steps`
  GpuGrid(const Context& context, int width, int height, int planes, Pass pass, const std::string& source, const std::string& name,
          int steps_per_dispatch = 1);
  virtual ~GpuGrid();
  GpuGrid(const GpuGrid&) = delete;
  GpuGrid& operator=(const GpuGrid&) = delete;
  // `count` passes; GL errors thrown as GlError
  void step(long count);
  // glFinish: the passes issued are done (for timing)
  void finish() const;

 protected:
  // plane p of the state, 4 floats a texel, row-major
  void upload_plane(int plane, const std::vector<float>& texels);
  void download_plane(int plane, std::vector<float>& texels) const;
  void uniform(const char* name, float value) const;
  // the program, current and in use, for the subclass's other uniforms
  unsigned use_program() const;
  const Gl& gl() const { return gl_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  const Context& context_;
  const Gl& gl_;
  int width_, height_, planes_;
  Pass pass_;
  int steps_per_dispatch_;
  std::vector<unsigned> textures_[2];  // each set's planes: textures, or a compute pass's storage buffers
  unsigned framebuffers_[2] = {0, 0};
  unsigned program_ = 0, vertex_array_ = 0;
  int current_ = 0;  // the set holding the state
};

// the backend the GPU methods make their contexts with: OSMesa, unless STEPWISE_GPU_BACKEND=egl; GlError
// for another value
gl::Backend backend();

// a context of that backend for a GPU method's run. On llvmpipe the passes are rasterised on the calling
// thread (LP_NUM_THREADS=0, unless the environment sets it; read when the process's first context is
// made): a run's thread CPU time is then its whole cost, as the report's work-precision diagrams count it,
// where llvmpipe's own threads would leave it uncounted; and a small grid's pass is cheaper without their
// hand-offs (the 6 x 6 sheet: 11 us a step against 58). On a GPU through EGL the device's time is not CPU
// time, and a run's cost counts only the host's part
std::unique_ptr<Context> make_device_context();

// "" or why a width x height grid cannot be stepped on `context` by a fragment pass: past its
// GL_MAX_TEXTURE_SIZE, or RGBA32F not a render target there; the limit named
std::string texture_problem(const Context& context, int width, int height);
// "" or why it cannot be stepped by a compute pass: no compute shaders (OpenGL before 4.3, the version named),
// or a plane past GL_MAX_SHADER_STORAGE_BLOCK_SIZE
std::string compute_grid_problem(const Context& context, int width, int height);
// the same asked of a context of the GPU methods' backend, made for the question, about the grid a GPU
// method would step for `system` (its wave grid or cloth grid); a context that cannot be made is the answer
std::string device_problem(const OdeSystem& system);
std::string compute_device_problem(const OdeSystem& system);

// a shader method's two entries in the method table: `name` as the seeds' fragment pass, and `name`-compute,
// its compute twin (the same bits: left out of the report's sweeps), each made by `stepper` with its kind and
// name (for its failures); the descriptions say what each pass computes, `stability` and `order` are the scheme's
struct ShaderMethod {
  std::string_view name, compute_name, description, compute_description;
  Order order;
  Requirement needs;
  Stability stability;
  std::function<std::unique_ptr<FixedStepper>(const CountedSystem& system, Pass pass, std::string_view name)> stepper;
};
void add_shader_methods(MethodTable& table, const ShaderMethod& method);

}  // namespace stepwise::gpu
