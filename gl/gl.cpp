#include "gl.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

namespace stepwise::gl {

Gl load_gl(void* (*get_proc)(const char* name)) {
  Gl gl;
#define STEPWISE_GL_LOAD(type, name)                                                   \
  gl.name = reinterpret_cast<type>(get_proc("gl" #name));                              \
  if (!gl.name) throw GlError("OpenGL 4.5: the context has no function gl" #name);
  STEPWISE_GL_FUNCTIONS(STEPWISE_GL_LOAD)
#undef STEPWISE_GL_LOAD
  return gl;
}

void check_gl(const Gl& gl, const std::string& what) {
  if (const GLenum code = gl.GetError(); code != GL_NO_ERROR) throw GlError(fmt::format("{}: glGetError() = 0x{:04x}", what, code));
}

namespace {

// a shader's or program's info log, through its pair of GL getters
template <class GetIv, class GetLog>
std::string info_log(GetIv get_iv, GetLog get_log, GLuint object) {
  GLint length = 0;
  get_iv(object, GL_INFO_LOG_LENGTH, &length);
  std::vector<char> log(static_cast<size_t>(std::max(length, 1)));
  get_log(object, length, nullptr, log.data());
  return log.data();
}

GLuint compile(const Gl& gl, GLenum stage, const char* source, const std::string& name) {
  const GLuint shader = gl.CreateShader(stage);
  gl.ShaderSource(shader, 1, &source, nullptr);
  gl.CompileShader(shader);
  GLint ok = 0;
  gl.GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    const std::string log = info_log(gl.GetShaderiv, gl.GetShaderInfoLog, shader);
    gl.DeleteShader(shader);
    const char* kind = stage == GL_VERTEX_SHADER ? "vertex" : stage == GL_GEOMETRY_SHADER ? "geometry" : stage == GL_COMPUTE_SHADER ? "compute" : "fragment";
    throw GlError(fmt::format("glCompileShader ({} shader of {}): {}", kind, name, log));
  }
  return shader;
}

// the program of `shaders`, which it deletes; GlError with the log
GLuint link(const Gl& gl, const std::vector<GLuint>& shaders, const std::string& name) {
  const GLuint program = gl.CreateProgram();
  for (const GLuint s : shaders) gl.AttachShader(program, s);
  gl.LinkProgram(program);
  for (const GLuint s : shaders) gl.DeleteShader(s);
  GLint ok = 0;
  gl.GetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    const std::string log = info_log(gl.GetProgramiv, gl.GetProgramInfoLog, program);
    gl.DeleteProgram(program);
    throw GlError(fmt::format("glLinkProgram ({}): {}", name, log));
  }
  return program;
}

}  // namespace

GLuint link_program(const Gl& gl, const char* vertex, const char* geometry, const char* fragment, const std::string& name) {
  std::vector<GLuint> shaders{compile(gl, GL_VERTEX_SHADER, vertex, name), compile(gl, GL_FRAGMENT_SHADER, fragment, name)};
  if (geometry && *geometry) shaders.push_back(compile(gl, GL_GEOMETRY_SHADER, geometry, name));
  return link(gl, shaders, name);
}

GLuint link_compute_program(const Gl& gl, const char* compute, const std::string& name) {
  return link(gl, {compile(gl, GL_COMPUTE_SHADER, compute, name)}, name);
}

std::string compute_problem(int major, int minor, const std::string& version) {
  if (major > 4 || (major == 4 && minor >= 3)) return {};
  return fmt::format("compute shaders need OpenGL 4.3; this GL is {}.{} ({})", major, minor, version);
}

std::string compute_problem(const Gl& gl) {
  GLint major = 0, minor = 0;
  gl.GetIntegerv(GL_MAJOR_VERSION, &major);
  gl.GetIntegerv(GL_MINOR_VERSION, &minor);
  const auto* text = reinterpret_cast<const char*>(gl.GetString(GL_VERSION));
  return compute_problem(major, minor, text ? text : "no GL_VERSION");
}

GLuint make_texture(const Gl& gl, GLenum format, int width, int height, GLenum wrap) {
  GLuint texture = 0;
  gl.CreateTextures(GL_TEXTURE_2D, 1, &texture);
  gl.TextureStorage2D(texture, 1, format, width, height);
  gl.TextureParameteri(texture, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  gl.TextureParameteri(texture, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl.TextureParameteri(texture, GL_TEXTURE_WRAP_S, static_cast<GLint>(wrap));
  gl.TextureParameteri(texture, GL_TEXTURE_WRAP_T, static_cast<GLint>(wrap));
  return texture;
}

}  // namespace stepwise::gl
