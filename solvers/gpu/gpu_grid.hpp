// What the GPU shader methods (issue 9) share: a grid's state in RGBA32F textures of its size, stepped by
// full-screen fragment passes that read one set of textures and write the other, then swap (ping-pong), on
// the GL context of gl/ (OSMesa's llvmpipe, or a GPU through EGL), which render/ uses too. They are solvers:
// they step model state, so they live here and not in render/. gpu_wave.cpp and gpu_cloth.cpp have the
// passes and register their methods; this file also has the device questions a run asks before it starts.
#pragma once

#include "gl/context.hpp"
#include "solvers/method.hpp"

#include <string>
#include <vector>

namespace stepwise::gpu {

using gl::Context;
using gl::Gl;

// a width x height grid's state in `planes` RGBA32F textures (plane p bound to texture unit p and written
// to colour attachment p), twice over, stepped by a fragment pass from one set into the other; texel (x, y)
// is the grid's row y, column x (the CPU grids' row-major cell y * width + x). `fragment`: the pass's GLSL
class GpuGrid {
 public:
  // GlError naming the limit where the grid passes GL_MAX_TEXTURE_SIZE, or where the context cannot render
  // to RGBA32F
  GpuGrid(const Context& context, int width, int height, int planes, const std::string& fragment, const std::string& name);
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
  std::vector<unsigned> textures_[2];  // each set's planes
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

// "" or why a width x height grid cannot be stepped on `context`: past its GL_MAX_TEXTURE_SIZE, or RGBA32F
// not a render target there; the limit named
std::string texture_problem(const Context& context, int width, int height);
// the same asked of a context of the GPU methods' backend, made for the question, about the grid a GPU
// method would step for `system` (its wave grid or cloth grid); a context that cannot be made is the answer
std::string device_problem(const OdeSystem& system);

}  // namespace stepwise::gpu
