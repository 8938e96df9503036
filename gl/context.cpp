#include "context.hpp"

#include <fmt/format.h>

namespace stepwise::gl {

std::optional<Backend> parse_backend(std::string_view name) {
  if (name == "osmesa") return Backend::osmesa;
  if (name == "egl") return Backend::egl;
  return std::nullopt;
}

bool Context::try_make_current() const noexcept {
  try {
    make_current();
    return true;
  } catch (const GlError&) {
    return false;
  }
}

std::string Context::description() const {
  make_current();
  const auto text = [&](GLenum what) {
    const GLubyte* s = gl_.GetString(what);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return fmt::format("{}, OpenGL {}", text(GL_RENDERER), text(GL_VERSION));
}

std::unique_ptr<Context> make_context(Backend backend) {
  return backend == Backend::osmesa ? make_osmesa_context() : make_egl_context();
}

}  // namespace stepwise::gl
