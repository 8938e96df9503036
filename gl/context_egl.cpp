// EGL on Mesa's surfaceless platform: no window system, no surface; drawing goes to framebuffer objects.
// Its types stay in this file.
#include "context.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <fmt/format.h>

namespace stepwise::gl {
namespace {

class EglContext final : public Context {
 public:
  EglContext() {
    const auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!get_display) throw GlError("eglGetProcAddress(eglGetPlatformDisplayEXT) returned NULL: EGL_EXT_platform_base is missing");
    display_ = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display_ == EGL_NO_DISPLAY)
      throw GlError(fmt::format("eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA) failed: 0x{:04x} (Mesa's EGL is needed: "
                                "apt-get install libegl-mesa0)", eglGetError()));
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display_, &major, &minor))
      throw GlError(fmt::format("eglInitialize failed: 0x{:04x} (apt-get install libegl-mesa0)", eglGetError()));
    if (!eglBindAPI(EGL_OPENGL_API)) fail("eglBindAPI(EGL_OPENGL_API)");
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5, EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    context_ = eglCreateContext(display_, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (context_ == EGL_NO_CONTEXT) fail("eglCreateContext (OpenGL 4.5 core, no config)");
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) fail("eglMakeCurrent (surfaceless)");
    gl_ = load_gl([](const char* name) { return reinterpret_cast<void*>(eglGetProcAddress(name)); });
  }
  ~EglContext() override { release(); }
  void make_current() const override {
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      throw GlError(fmt::format("eglMakeCurrent (surfaceless) failed: 0x{:04x}", eglGetError()));
  }
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

 private:
  [[noreturn]] void fail(const char* call) {
    const EGLint code = eglGetError();
    release();
    throw GlError(fmt::format("{} failed: 0x{:04x}", call, code));
  }
  void release() {
    if (context_ != EGL_NO_CONTEXT) {
      eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      eglDestroyContext(display_, context_);
    }
    eglTerminate(display_);
  }
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
};

}  // namespace

std::unique_ptr<Context> make_egl_context() { return std::make_unique<EglContext>(); }

}  // namespace stepwise::gl
