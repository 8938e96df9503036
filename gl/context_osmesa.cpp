// OSMesa: Mesa's off-screen context, drawing with llvmpipe. Its types stay in this file.
#include "context.hpp"

#include <GL/osmesa.h>

#include <fmt/format.h>

#include <array>

namespace stepwise::gl {
namespace {

class OsmesaContext final : public Context {
 public:
  OsmesaContext() {
    const int attributes[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                              OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
    context_ = OSMesaCreateContextAttribs(attributes, nullptr);
    if (!context_)
      throw GlError("OSMesaCreateContextAttribs (OpenGL 4.5 core) returned NULL: Mesa's llvmpipe is needed "
                    "(apt-get install libosmesa6), or try --backend egl");
    try {
      make_current();
    } catch (const GlError&) {
      OSMesaDestroyContext(context_);
      throw;
    }
    gl_ = load_gl([](const char* name) { return reinterpret_cast<void*>(OSMesaGetProcAddress(name)); });
  }
  ~OsmesaContext() override { OSMesaDestroyContext(context_); }
  // drawing goes to framebuffer objects; the context only needs some buffer to be current with
  void make_current() const override {
    if (!OSMesaMakeCurrent(context_, pixel_.data(), GL_UNSIGNED_BYTE, 1, 1)) throw GlError("OSMesaMakeCurrent returned GL_FALSE");
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
