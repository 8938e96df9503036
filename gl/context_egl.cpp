// EGL with no window system and no surface; drawing goes to framebuffer objects. Mesa's surfaceless platform
// first (llvmpipe here); where no vendor offers it (NVIDIA's EGL, behind glvnd, does not), the first device of
// EGL_EXT_platform_device that initialises: a GPU's driver without a display. Its types stay in this file.
#include "context.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <fmt/format.h>

#include <dlfcn.h>
#include <link.h>

#include <map>
#include <mutex>
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

// the first device EGL_EXT_device_enumeration lists whose display initialises, or EGL_NO_DISPLAY
EGLDisplay device_display(PFNEGLGETPLATFORMDISPLAYEXTPROC get_display) {
  const auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  if (!query_devices) return EGL_NO_DISPLAY;
  EGLDeviceEXT devices[16];
  EGLint count = 0;
  if (!query_devices(16, devices, &count)) return EGL_NO_DISPLAY;
  for (EGLint i = 0; i < count; ++i) {
    const EGLDisplay display = get_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
    EGLint major = 0, minor = 0;
    if (display != EGL_NO_DISPLAY && eglInitialize(display, &major, &minor)) return display;
  }
  return EGL_NO_DISPLAY;
}

// An EGL display is the process's (every context on a device gets the same handle) and eglTerminate ends every
// context on it, another thread's too: each context holds it, and the last one to let go terminates it. (Seen on
// NVIDIA's EGL: a GPU method's context, made and dropped inside a test, left the test's own context
// EGL_NOT_INITIALIZED.) Taking a display, initialising and holding it are one step under the lock, so no
// terminate falls between them
std::mutex& display_mutex() {
  static std::mutex m;
  return m;
}
std::map<EGLDisplay, int>& display_holders() {
  static std::map<EGLDisplay, int> holders;
  return holders;
}

class EglContext final : public Context {
 public:
  EglContext() {
    std::unique_lock lock(display_mutex());
    const auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!get_display) throw GlError("eglGetProcAddress(eglGetPlatformDisplayEXT) returned NULL: EGL_EXT_platform_base is missing");
    EGLint major = 0, minor = 0;
    display_ = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    const EGLint surfaceless_error = display_ == EGL_NO_DISPLAY ? eglGetError() : EGL_SUCCESS;
    if (display_ == EGL_NO_DISPLAY || !eglInitialize(display_, &major, &minor)) {
      display_ = device_display(get_display);
      if (display_ == EGL_NO_DISPLAY)
        throw GlError(fmt::format("eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA) failed: 0x{:04x}, and no EGL device initialised "
                                  "(Mesa's EGL is needed: apt-get install libegl-mesa0)",
                                  surfaceless_error == EGL_SUCCESS ? eglGetError() : surfaceless_error));
    }
    ++display_holders()[display_];
    lock.unlock();
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
    const std::lock_guard lock(display_mutex());
    if (--display_holders()[display_] == 0) {
      display_holders().erase(display_);
      eglTerminate(display_);
    }
  }
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
};

}  // namespace

std::unique_ptr<Context> make_egl_context() { return std::make_unique<EglContext>(); }

}  // namespace stepwise::gl
