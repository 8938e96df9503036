// OSMesa: Mesa's off-screen context, drawing with llvmpipe. Its types stay in this file.
//
// The library is opened when the first context is made, not linked: a program that draws through EGL (a GPU's
// driver, on a machine without Mesa; Mesa from 25.1 on, which has no OSMesa) starts without it, and one
// that asks for OSMesa where it is missing gets a GlError naming the package.
#include "context.hpp"

#include <GL/osmesa.h>

#include <fmt/format.h>

#include <dlfcn.h>

#include <array>

namespace stepwise::gl {
namespace {

// the four calls made here, from libOSMesa.so.8, opened once for the process and never closed (Mesa keeps
// state for the process's life: verification/lsan.supp)
struct Osmesa {
  decltype(&OSMesaCreateContextAttribs) create_context_attribs;
  decltype(&OSMesaMakeCurrent) make_current;
  decltype(&OSMesaDestroyContext) destroy_context;
  decltype(&OSMesaGetProcAddress) get_proc_address;
};

const Osmesa& osmesa() {
  static const Osmesa library = [] {
    constexpr const char* soname = "libOSMesa.so.8";
    void* handle = dlopen(soname, RTLD_NOW | RTLD_LOCAL);
    if (!handle)
      throw GlError(fmt::format("dlopen({}) failed: {} (apt-get install libosmesa6, or try --backend egl)", soname, dlerror()));
    const auto symbol = [&]<class F>(F*& f, const char* name) {
      f = reinterpret_cast<F*>(dlsym(handle, name));
      if (!f) throw GlError(fmt::format("dlsym({}, {}) returned NULL: {}", soname, name, dlerror()));
    };
    Osmesa o{};
    symbol(o.create_context_attribs, "OSMesaCreateContextAttribs");
    symbol(o.make_current, "OSMesaMakeCurrent");
    symbol(o.destroy_context, "OSMesaDestroyContext");
    symbol(o.get_proc_address, "OSMesaGetProcAddress");
    return o;
  }();
  return library;
}

class OsmesaContext final : public Context {
 public:
  OsmesaContext() {
    const int attributes[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                              OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
    context_ = osmesa().create_context_attribs(attributes, nullptr);
    if (!context_)
      throw GlError("OSMesaCreateContextAttribs (OpenGL 4.5 core) returned NULL: Mesa's llvmpipe is needed "
                    "(apt-get install libosmesa6), or try --backend egl");
    try {
      make_current();
    } catch (const GlError&) {
      osmesa().destroy_context(context_);
      throw;
    }
    gl_ = load_gl([](const char* name) { return reinterpret_cast<void*>(osmesa().get_proc_address(name)); });
  }
  ~OsmesaContext() override { osmesa().destroy_context(context_); }
  // drawing goes to framebuffer objects; the context only needs some buffer to be current with
  void make_current() const override {
    if (!osmesa().make_current(context_, pixel_.data(), GL_UNSIGNED_BYTE, 1, 1)) throw GlError("OSMesaMakeCurrent returned GL_FALSE");
  }
  OsmesaContext(const OsmesaContext&) = delete;
  OsmesaContext& operator=(const OsmesaContext&) = delete;

 private:
  OSMesaContext context_ = nullptr;
  mutable std::array<unsigned char, 4> pixel_{};
};

}  // namespace

std::unique_ptr<Context> make_osmesa_context() { return std::make_unique<OsmesaContext>(); }

}  // namespace stepwise::gl
