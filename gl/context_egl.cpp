// EGL on Mesa's surfaceless platform: no window system, no surface; drawing goes to framebuffer objects.
// Its types stay in this file.
#include "context.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <fmt/format.h>

#include <dlfcn.h>
#include <link.h>

#include <string_view>

namespace stepwise::gl {
namespace {

// Mesa's EGL loads its driver (swrast_dri.so and the like, from a dri/ directory) at eglInitialize and unloads
// it at eglTerminate, while 240 bytes the driver allocated (a 128-byte realloc, two 56-byte callocs) are still
// referenced only from its own data: unmapped, they became a leak LeakSanitizer reported from an unloaded,
// unnameable module, which no suppression can match. Kept mapped (it is loaded once per process anyway), the
// driver's data still references them: no leak, measured, and nothing to suppress.
void keep_drivers_loaded() {
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void*) {
        const std::string_view path = info->dlpi_name ? info->dlpi_name : "";
        if (path.find("/dri/") != std::string_view::npos) dlopen(info->dlpi_name, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
        return 0;
      },
      nullptr);
}

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
    keep_drivers_loaded();
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
