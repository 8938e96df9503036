#include "gpu_grid.hpp"

#include "solvers/method.hpp"

#include "gpu_cloth.hpp"
#include "gpu_vbd.hpp"
#include "gpu_wave.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <mutex>

namespace stepwise::gpu {

using gl::Backend;
using gl::GlError;
using gl::check_gl;
using gl::link_program;
using gl::make_context;
using gl::parse_backend;

namespace {

// a triangle covering the viewport, from the vertex index alone
const char* const full_screen = R"(#version 450
void main() {
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
}
)";

}  // namespace

std::string texture_problem(const Context& context, int width, int height) {
  context.make_current();
  const Gl& gl = context.gl();
  GLint max_size = 0;
  gl.GetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (width > max_size || height > max_size)
    return fmt::format("a {} x {} grid passes this GL's largest texture, GL_MAX_TEXTURE_SIZE = {}", width, height, max_size);
  GLuint texture = 0, framebuffer = 0;
  gl.CreateTextures(GL_TEXTURE_2D, 1, &texture);
  gl.TextureStorage2D(texture, 1, GL_RGBA32F, 1, 1);
  gl.CreateFramebuffers(1, &framebuffer);
  gl.NamedFramebufferTexture(framebuffer, GL_COLOR_ATTACHMENT0, texture, 0);
  const GLenum status = gl.CheckNamedFramebufferStatus(framebuffer, GL_FRAMEBUFFER);
  gl.DeleteFramebuffers(1, &framebuffer);
  gl.DeleteTextures(1, &texture);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    return fmt::format("this GL cannot render to float textures (RGBA32F): glCheckNamedFramebufferStatus = 0x{:04x}", status);
  return {};
}

std::string compute_prelude() {
  return fmt::format("#version 450\nlayout(local_size_x = {0}, local_size_y = {0}) in;\nuniform ivec2 size;\nivec2 grid_size() {{ return size; }}\n", tile);
}

std::string compute_grid_problem(const Context& context, int width, int height) {
  context.make_current();
  const Gl& gl = context.gl();
  if (std::string problem = gl::compute_problem(gl); !problem.empty()) return problem;
  GLint64 max_bytes = 0;
  gl.GetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_bytes);
  const double bytes = 16.0 * width * height;
  if (bytes > static_cast<double>(max_bytes))
    return fmt::format("a {} x {} grid's plane ({:.3g} MB of vec4) passes this GL's largest storage buffer, GL_MAX_SHADER_STORAGE_BLOCK_SIZE = {} bytes",
                       width, height, bytes / 1e6, max_bytes);
  return {};
}

GpuGrid::GpuGrid(const Context& context, int width, int height, int planes, Pass pass, const std::string& source, const std::string& name,
                 int steps_per_dispatch)
    : context_(context), gl_(context.gl()), width_(width), height_(height), planes_(planes), pass_(pass), steps_per_dispatch_(steps_per_dispatch) {
  if (pass == Pass::compute) {
    if (const std::string problem = compute_grid_problem(context, width, height); !problem.empty()) throw GlError(problem);
    const auto bytes = static_cast<GLsizeiptr>(16) * width * height;
    for (auto& set : textures_) {
      set.resize(planes);
      gl_.CreateBuffers(planes, set.data());
      for (const unsigned buffer : set) gl_.NamedBufferStorage(buffer, bytes, nullptr, GL_DYNAMIC_STORAGE_BIT);
    }
    program_ = gl::link_compute_program(gl_, source.c_str(), name);
    gl_.UseProgram(program_);
    gl_.Uniform2i(gl_.GetUniformLocation(program_, "size"), width, height);
    check_gl(gl_, fmt::format("the {}'s buffers and program", name));
    return;
  }
  if (const std::string problem = texture_problem(context, width, height); !problem.empty()) throw GlError(problem);
  gl_.CreateFramebuffers(2, framebuffers_);
  std::vector<GLenum> attachments;
  for (int p = 0; p < planes; ++p) attachments.push_back(GL_COLOR_ATTACHMENT0 + p);
  for (int set = 0; set < 2; ++set) {
    textures_[set].resize(planes);
    gl_.CreateTextures(GL_TEXTURE_2D, planes, textures_[set].data());
    for (int p = 0; p < planes; ++p) {
      gl_.TextureStorage2D(textures_[set][p], 1, GL_RGBA32F, width, height);
      // one level and texelFetch: no filtering, and a texture complete without mipmaps
      gl_.TextureParameteri(textures_[set][p], GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      gl_.TextureParameteri(textures_[set][p], GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      gl_.NamedFramebufferTexture(framebuffers_[set], attachments[p], textures_[set][p], 0);
    }
    gl_.NamedFramebufferDrawBuffers(framebuffers_[set], planes, attachments.data());
    if (const GLenum status = gl_.CheckNamedFramebufferStatus(framebuffers_[set], GL_FRAMEBUFFER); status != GL_FRAMEBUFFER_COMPLETE)
      throw GlError(fmt::format("this context cannot render to float textures: glCheckNamedFramebufferStatus ({} RGBA32F {} x {}) = 0x{:04x}",
                                planes, width, height, status));
  }
  program_ = link_program(gl_, full_screen, nullptr, source.c_str(), name);
  gl_.CreateVertexArrays(1, &vertex_array_);
  check_gl(gl_, fmt::format("the {}'s textures and program", name));
}

GpuGrid::~GpuGrid() {
  if (!context_.try_make_current()) return;
  gl_.DeleteProgram(program_);
  if (pass_ == Pass::compute) {
    for (auto& set : textures_) gl_.DeleteBuffers(static_cast<GLsizei>(set.size()), set.data());
    return;
  }
  gl_.DeleteVertexArrays(1, &vertex_array_);
  gl_.DeleteFramebuffers(2, framebuffers_);
  for (auto& set : textures_) gl_.DeleteTextures(static_cast<GLsizei>(set.size()), set.data());
}

unsigned GpuGrid::use_program() const {
  context_.make_current();
  gl_.UseProgram(program_);
  return program_;
}

void GpuGrid::uniform(const char* name, float value) const { gl_.Uniform1f(gl_.GetUniformLocation(use_program(), name), value); }

void GpuGrid::upload_plane(int plane, const std::vector<float>& texels) {
  context_.make_current();
  if (pass_ == Pass::compute) {
    gl_.NamedBufferSubData(textures_[current_][plane], 0, static_cast<GLsizeiptr>(texels.size() * sizeof(float)), texels.data());
    check_gl(gl_, "glNamedBufferSubData (a grid's state)");
    return;
  }
  gl_.TextureSubImage2D(textures_[current_][plane], 0, 0, 0, width_, height_, GL_RGBA, GL_FLOAT, texels.data());
  check_gl(gl_, "glTextureSubImage2D (a grid's state)");
}

void GpuGrid::step(long count) {
  context_.make_current();
  gl_.UseProgram(program_);
  if (pass_ == Pass::compute) {
    const auto groups = [](int cells) { return static_cast<GLuint>((cells + tile - 1) / tile); };
    const GLint pass_steps = steps_per_dispatch_ > 1 ? gl_.GetUniformLocation(program_, "pass_steps") : -1;
    for (long left = count; left > 0;) {
      const long steps = std::min<long>(left, steps_per_dispatch_);
      if (pass_steps >= 0) gl_.Uniform1i(pass_steps, static_cast<GLint>(steps));
      left -= steps;
      for (int p = 0; p < planes_; ++p) {
        gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, static_cast<GLuint>(p), textures_[current_][p]);
        gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, static_cast<GLuint>(4 + p), textures_[1 - current_][p]);
      }
      gl_.DispatchCompute(groups(width_), groups(height_), 1);
      // the next pass reads what this one wrote
      gl_.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
      current_ = 1 - current_;
    }
    check_gl(gl_, "a grid pass (glDispatchCompute)");
    return;
  }
  gl_.Disable(GL_BLEND);
  gl_.Disable(GL_DEPTH_TEST);
  gl_.Disable(GL_CULL_FACE);
  gl_.Viewport(0, 0, width_, height_);
  gl_.BindVertexArray(vertex_array_);
  for (long s = 0; s < count; ++s) {
    gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffers_[1 - current_]);
    for (int p = 0; p < planes_; ++p) gl_.BindTextureUnit(p, textures_[current_][p]);
    gl_.DrawArrays(GL_TRIANGLES, 0, 3);
    current_ = 1 - current_;
  }
  for (int p = 0; p < planes_; ++p) gl_.BindTextureUnit(p, 0);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
  check_gl(gl_, "a grid pass (glDrawArrays)");
}

void GpuGrid::finish() const {
  context_.make_current();
  gl_.Finish();
}

void GpuGrid::download_plane(int plane, std::vector<float>& texels) const {
  context_.make_current();
  texels.resize(4 * static_cast<size_t>(width_) * static_cast<size_t>(height_));
  if (pass_ == Pass::compute) {
    gl_.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    gl_.GetNamedBufferSubData(textures_[current_][plane], 0, static_cast<GLsizeiptr>(texels.size() * sizeof(float)), texels.data());
    check_gl(gl_, "glGetNamedBufferSubData (a grid's state)");
    return;
  }
  gl_.GetTextureImage(textures_[current_][plane], 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(texels.size() * sizeof(float)), texels.data());
  check_gl(gl_, "glGetTextureImage (a grid's state)");
}

Backend backend() {
  const char* name = std::getenv("STEPWISE_GPU_BACKEND");
  if (!name || !*name) return Backend::osmesa;
  if (const auto b = parse_backend(name)) return *b;
  throw GlError(fmt::format("STEPWISE_GPU_BACKEND must be osmesa or egl, got '{}'", name));
}

std::unique_ptr<Context> make_device_context() {
  static std::once_flag once;
  std::call_once(once, [] { setenv("LP_NUM_THREADS", "0", 0); });
  return make_context(backend());
}

namespace {

// the device question `problem` asked about the grid a GPU method would step for `system`
std::string grid_problem(const OdeSystem& system, std::string (*problem)(const Context&, int, int)) {
  int width = 0, height = 0;
  if (const auto* grid = system.as<WaveGridView>()) width = height = grid->points;
  else if (const auto* cloth = system.as<ClothGridView>()) width = cloth->columns, height = cloth->rows;
  else return "no grid a GPU method steps (a water or cloth scene)";
  try {
    return problem(*make_device_context(), width, height);
  } catch (const GlError& e) {
    return e.what();
  }
}

}  // namespace

std::string device_problem(const OdeSystem& system) { return grid_problem(system, texture_problem); }
std::string compute_device_problem(const OdeSystem& system) { return grid_problem(system, compute_grid_problem); }

void add_shader_methods(MethodTable& table, const ShaderMethod& m) {
  for (const Pass pass : {Pass::fragment, Pass::compute}) {
    const bool compute = pass == Pass::compute;
    const std::string_view name = compute ? m.compute_name : m.name;
    table.add({
        .name = name,
        .family = Family::gpu,
        .source = Source::opengl_shader,
        .description = compute ? m.compute_description : m.description,
        .order = m.order,
        .stepping = Stepping::fixed,
        .needs = m.needs,
        .make = fixed_steps([stepper = m.stepper, pass, name](const CountedSystem& system) { return stepper(system, pass, name); }),
        .stability = m.stability,
        .device_problem = compute ? compute_device_problem : device_problem,
        .twin = compute ? m.name : std::string_view(),
    });
  }
}

}  // namespace stepwise::gpu

namespace stepwise {

// the gpu family (solvers/CMakeLists.txt's list): the wave's and the cloth's passes, and vbd's sweeps
void register_gpu_methods(MethodTable& table) {
  gpu::register_wave_methods(table);
  gpu::register_cloth_methods(table);
  gpu::register_vbd_compute_method(table);
}

}  // namespace stepwise
