#include "caustics.hpp"

#include "water_optics.hpp"

#include <fmt/format.h>

#include <string>

namespace stepwise::render {
namespace {

// each vertex refracted along the light onto the floor
constexpr const char* vertex_shader = R"(#version 450 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
uniform vec3 light;
uniform float depth, index;
out vec3 surface, floor_point;
void main() {
  vec3 t = refract(-light, normalize(normal), 1.0 / index);
  surface = position;
  floor_point = position + t * ((-depth - position.z) / t.z);
  gl_Position = vec4(0.0);
}
)";

// the triangle's transmitted power over its projected area, flat across the projected triangle
constexpr const char* geometry_shader_body = R"(
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;
in vec3 surface[], floor_point[];
uniform vec3 light;
uniform float index, side;
flat out float irradiance;
void main() {
  vec3 area_vector = 0.5 * cross(surface[1] - surface[0], surface[2] - surface[0]);
  float area = length(area_vector);
  if (area == 0.0) return;
  vec3 face = area_vector / area * sign(area_vector.z);
  float cos_i = dot(face, light);
  if (cos_i <= 0.0) return;
  vec2 a = floor_point[1].xy - floor_point[0].xy, b = floor_point[2].xy - floor_point[0].xy;
  float projected = 0.5 * abs(a.x * b.y - a.y * b.x);
  if (projected == 0.0) return;
  float value = area * cos_i * fresnel_transmittance(cos_i, index) / projected;
  for (int k = 0; k < 3; ++k) {
    irradiance = value;
    gl_Position = vec4(floor_point[k].xy / side * 2.0 - 1.0, 0.0, 1.0);
    EmitVertex();
  }
  EndPrimitive();
}
)";

constexpr const char* fragment_shader = R"(#version 450 core
flat in float irradiance;
out vec4 color;
void main() { color = vec4(irradiance, 0.0, 0.0, 1.0); }
)";

}  // namespace

PhotonMap::PhotonMap(const gl::Context& context, int resolution) : context_(context), gl_(context.gl()), resolution_(resolution) {
  context_.make_current();
  const std::string geometry = std::string("#version 450 core\n") + glsl_fresnel + geometry_shader_body;
  program_ = gl::link_program(gl_, vertex_shader, geometry.c_str(), fragment_shader, "photon map");
  texture_ = gl::make_texture(gl_, GL_RGBA32F, resolution, resolution, GL_CLAMP_TO_EDGE);
  gl_.CreateFramebuffers(1, &framebuffer_);
  gl_.NamedFramebufferTexture(framebuffer_, GL_COLOR_ATTACHMENT0, texture_, 0);
  if (const GLenum status = gl_.CheckNamedFramebufferStatus(framebuffer_, GL_FRAMEBUFFER); status != GL_FRAMEBUFFER_COMPLETE)
    throw gl::GlError(fmt::format("glCheckNamedFramebufferStatus (photon map, RGBA32F {}^2) = 0x{:04x}", resolution, status));
  gl_.CreateVertexArrays(1, &vertex_array_);
  gl_.CreateBuffers(1, &buffer_);
  gl_.VertexArrayVertexBuffer(vertex_array_, 0, buffer_, 0, 6 * sizeof(float));
  for (GLuint a = 0; a < 2; ++a) {
    gl_.EnableVertexArrayAttrib(vertex_array_, a);
    gl_.VertexArrayAttribFormat(vertex_array_, a, 3, GL_FLOAT, GL_FALSE, 3 * a * sizeof(float));
    gl_.VertexArrayAttribBinding(vertex_array_, a, 0);
  }
  gl::check_gl(gl_, "photon map set-up");
}

PhotonMap::~PhotonMap() {
  if (!context_.try_make_current()) return;  // the objects are this context's
  gl_.DeleteBuffers(1, &buffer_);
  gl_.DeleteVertexArrays(1, &vertex_array_);
  gl_.DeleteFramebuffers(1, &framebuffer_);
  gl_.DeleteTextures(1, &texture_);
  gl_.DeleteProgram(program_);
}

void PhotonMap::build(const Shapes::Water& water, const Eigen::Vector3d& light, double depth) {
  // the surface as triangles, two per grid cell, each vertex its position and normal
  const int n = water.points;
  const auto normals = height_field_normals(water);
  std::vector<float>& vertices = vertices_;
  vertices.clear();
  vertices.reserve(static_cast<size_t>(n - 1) * (n - 1) * 36);
  const auto push = [&](int i, int j) {
    const Eigen::Index k = static_cast<Eigen::Index>(i) * n + j;
    for (const double v : {j * water.spacing, i * water.spacing, water.z[k], normals(k, 0), normals(k, 1), normals(k, 2)})
      vertices.push_back(static_cast<float>(v));
  };
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j + 1 < n; ++j) {
      push(i, j), push(i, j + 1), push(i + 1, j + 1);
      push(i, j), push(i + 1, j + 1), push(i + 1, j);
    }
  gl_.NamedBufferData(buffer_, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)), vertices.data(), GL_STREAM_DRAW);

  context_.make_current();
  const float zero[4] = {0, 0, 0, 0};
  gl_.ClearNamedFramebufferfv(framebuffer_, GL_COLOR, 0, zero);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  gl_.Viewport(0, 0, resolution_, resolution_);
  gl_.Disable(GL_DEPTH_TEST);
  gl_.Disable(GL_CULL_FACE);
  gl_.Enable(GL_BLEND);
  gl_.BlendFunc(GL_ONE, GL_ONE);
  gl_.UseProgram(program_);
  const Eigen::Vector3f l = light.normalized().cast<float>();
  gl_.Uniform3fv(gl_.GetUniformLocation(program_, "light"), 1, l.data());
  gl_.Uniform1f(gl_.GetUniformLocation(program_, "depth"), static_cast<float>(depth));
  gl_.Uniform1f(gl_.GetUniformLocation(program_, "index"), static_cast<float>(water_index));
  gl_.Uniform1f(gl_.GetUniformLocation(program_, "side"), static_cast<float>((n - 1) * water.spacing));
  gl_.BindVertexArray(vertex_array_);
  gl_.DrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(vertices.size() / 6));
  gl_.Disable(GL_BLEND);
  gl::check_gl(gl_, "photon map pass (glDrawArrays)");
}

std::vector<float> PhotonMap::read() const {
  context_.make_current();
  std::vector<float> map(static_cast<size_t>(resolution_) * resolution_);
  gl_.GetTextureImage(texture_, 0, GL_RED, GL_FLOAT, static_cast<GLsizei>(map.size() * sizeof(float)), map.data());
  gl::check_gl(gl_, "glGetTextureImage (photon map)");
  return map;
}

}  // namespace stepwise::render
