// An offscreen OpenGL 4.5 core context, made current on the calling thread when made and by make_current(): OSMesa (the default) or
// EGL on Mesa's surfaceless platform, which gives the same images and is the path that outlives OSMesa
// (removed in Mesa 25.1) and reaches a real GPU. Drawing goes to framebuffer objects, never to a window.
#pragma once

#include "gl.hpp"

#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace stepwise::gl {

enum class Backend { osmesa, egl };

// "osmesa" | "egl"
std::optional<Backend> parse_backend(std::string_view name);

class Context {
 public:
  virtual ~Context() = default;
  const Gl& gl() const { return gl_; }
  // makes this the calling thread's current context (another may have been made current since); GlError if
  // it cannot be
  virtual void make_current() const = 0;
  // make_current for a destructor: false (and nothing thrown) if it cannot be
  bool try_make_current() const noexcept;
  // GL_RENDERER and GL_VERSION ("llvmpipe (LLVM 15.0.6, 256 bits), 4.5 (Core Profile) Mesa 22.3.6")
  std::string description() const;

 protected:
  Gl gl_;
};

// GlError naming the call that failed and, where a library is missing, the package that brings it
std::unique_ptr<Context> make_context(Backend backend);
std::unique_ptr<Context> make_osmesa_context();
std::unique_ptr<Context> make_egl_context();

}  // namespace stepwise::gl
