#include "gpu_wave.hpp"

#include "solvers/wave_fd.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <vector>

namespace stepwise::render {

namespace {

// a triangle covering the viewport, from the vertex index alone
const char* const full_screen = R"(#version 450
void main() {
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
}
)";

// texel (x, y) is cell i * points + j with x = j, y = i: rows (i) apart along y, as z[j -+ n] on the CPU
const char* const wave_pass = R"(#version 450
layout(binding = 0) uniform sampler2D state;
uniform float k_self, k_previous, k_neighbours;
layout(location = 0) out vec4 next;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 size = textureSize(state, 0);
  vec4 here = texelFetch(state, p, 0);
  if (p.x == 0 || p.y == 0 || p.x == size.x - 1 || p.y == size.y - 1) {
    next = vec4(here.r, here.r, 0.0, 0.0);
    return;
  }
  precise float down_up = texelFetch(state, p - ivec2(0, 1), 0).r + texelFetch(state, p + ivec2(0, 1), 0).r;
  precise float left_right = texelFetch(state, p - ivec2(1, 0), 0).r + texelFetch(state, p + ivec2(1, 0), 0).r;
  precise float sum = down_up + left_right;
  precise float a = k_self * here.r;
  precise float b = k_previous * here.g;
  precise float c = k_neighbours * sum;
  precise float z1 = (a + b) + c;
  next = vec4(z1, here.r, 0.0, 0.0);
}
)";

}  // namespace

GpuWave::GpuWave(const Context& context, int points, const BasicWaveCoefficients<float>& k)
    : context_(context), gl_(context.gl()), points_(points) {
  context_.make_current();
  GLint max_size = 0;
  gl_.GetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (points > max_size)
    throw GlError(fmt::format("a {} x {} grid passes this GL's largest texture, GL_MAX_TEXTURE_SIZE = {}", points, points, max_size));
  gl_.CreateTextures(GL_TEXTURE_2D, 2, textures_);
  gl_.CreateFramebuffers(2, framebuffers_);
  for (int t = 0; t < 2; ++t) {
    gl_.TextureStorage2D(textures_[t], 1, GL_RGBA32F, points, points);
    // one level and texelFetch: no filtering, and a texture complete without mipmaps
    gl_.TextureParameteri(textures_[t], GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl_.TextureParameteri(textures_[t], GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl_.NamedFramebufferTexture(framebuffers_[t], GL_COLOR_ATTACHMENT0, textures_[t], 0);
    if (const GLenum status = gl_.CheckNamedFramebufferStatus(framebuffers_[t], GL_FRAMEBUFFER); status != GL_FRAMEBUFFER_COMPLETE)
      throw GlError(fmt::format("this context cannot render to float textures: glCheckNamedFramebufferStatus (RGBA32F {}^2) = 0x{:04x}", points, status));
  }
  program_ = link_program(gl_, full_screen, nullptr, wave_pass, "wave pass");
  gl_.CreateVertexArrays(1, &vertex_array_);
  set_coefficients(k);
  check_gl(gl_, "the wave pass's textures and program");
}

void GpuWave::set_coefficients(const BasicWaveCoefficients<float>& k) {
  context_.make_current();
  gl_.UseProgram(program_);
  gl_.Uniform1f(gl_.GetUniformLocation(program_, "k_self"), k.self);
  gl_.Uniform1f(gl_.GetUniformLocation(program_, "k_previous"), k.previous);
  gl_.Uniform1f(gl_.GetUniformLocation(program_, "k_neighbours"), k.neighbours);
}

GpuWave::~GpuWave() {
  if (!context_.try_make_current()) return;
  gl_.DeleteVertexArrays(1, &vertex_array_);
  gl_.DeleteProgram(program_);
  gl_.DeleteFramebuffers(2, framebuffers_);
  gl_.DeleteTextures(2, textures_);
}

void GpuWave::upload(const Eigen::VectorXf& z_prev, const Eigen::VectorXf& z) {
  context_.make_current();
  std::vector<float> texels(4 * static_cast<size_t>(z.size()));
  for (Eigen::Index c = 0; c < z.size(); ++c) {
    texels[4 * c] = z[c];
    texels[4 * c + 1] = z_prev[c];
  }
  gl_.TextureSubImage2D(textures_[current_], 0, 0, 0, points_, points_, GL_RGBA, GL_FLOAT, texels.data());
  check_gl(gl_, "glTextureSubImage2D (the wave's state)");
}

void GpuWave::step(long count) {
  context_.make_current();
  gl_.Disable(GL_BLEND);
  gl_.Disable(GL_DEPTH_TEST);
  gl_.Disable(GL_CULL_FACE);
  gl_.Viewport(0, 0, points_, points_);
  gl_.UseProgram(program_);
  gl_.BindVertexArray(vertex_array_);
  for (long s = 0; s < count; ++s) {
    gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffers_[1 - current_]);
    gl_.BindTextureUnit(0, textures_[current_]);
    gl_.DrawArrays(GL_TRIANGLES, 0, 3);
    current_ = 1 - current_;
  }
  gl_.BindTextureUnit(0, 0);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
  check_gl(gl_, "the wave pass (glDrawArrays)");
}

void GpuWave::finish() const {
  context_.make_current();
  gl_.Finish();
}

void GpuWave::download(Eigen::VectorXf& z_prev, Eigen::VectorXf& z) const {
  context_.make_current();
  const Eigen::Index cells = static_cast<Eigen::Index>(points_) * points_;
  std::vector<float> texels(4 * static_cast<size_t>(cells));
  gl_.GetTextureImage(textures_[current_], 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(texels.size() * sizeof(float)), texels.data());
  check_gl(gl_, "glGetTextureImage (the wave's state)");
  z.resize(cells);
  z_prev.resize(cells);
  for (Eigen::Index c = 0; c < cells; ++c) {
    z[c] = texels[4 * c];
    z_prev[c] = texels[4 * c + 1];
  }
}

namespace {

// gpu-wave: the levels live on the GL device between steps; each step is one pass, and the new level is
// read back for the state the run samples (z^{k+1}, and the velocity from it on the CPU)
class GpuWaveStepper final : public ThreeLevelWaveStepper {
 public:
  using ThreeLevelWaveStepper::ThreeLevelWaveStepper;

 private:
  static Backend backend() {
    const char* name = std::getenv("STEPWISE_GPU_BACKEND");
    if (!name || !*name) return Backend::osmesa;
    if (const auto b = parse_backend(name)) return *b;
    throw GlError(fmt::format("STEPWISE_GPU_BACKEND must be osmesa or egl, got '{}'", name));
  }
  bool advance(const WaveCoefficients& k, const double* z_prev, const double* z, double* z_next, bool fresh, std::string& failure) override {
    const int n = grid().points;
    const Eigen::Index cells = static_cast<Eigen::Index>(n) * n;
    try {
      if (!context_) context_ = make_context(backend());
      if (!gpu_) gpu_ = std::make_unique<GpuWave>(*context_, n, to_float(k));
      if (fresh) {
        gpu_->set_coefficients(to_float(k));
        gpu_->upload(Eigen::Map<const Eigen::VectorXd>(z_prev, cells).cast<float>(), Eigen::Map<const Eigen::VectorXd>(z, cells).cast<float>());
      }
      gpu_->step(1);
      gpu_->download(level_prev_, level_);
    } catch (const GlError& e) {
      failure = fmt::format("gpu-wave: {}", e.what());
      return false;
    }
    Eigen::Map<Eigen::VectorXd>(z_next, cells) = level_.cast<double>();
    return true;
  }
  std::unique_ptr<Context> context_;
  std::unique_ptr<GpuWave> gpu_;
  Eigen::VectorXf level_prev_, level_;
};

}  // namespace

void register_gpu_methods() {
  register_stepper("gpu-wave", [](const CountedSystem& system) { return std::make_unique<GpuWaveStepper>(system); });
}

}  // namespace stepwise::render
