// OSMesa (Mesa's llvmpipe without a window system). The context only exists to
// host the Renderer's framebuffer object, so its own surface is a single pixel.
#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/osmesa.h>

#include <array>
#include <stdexcept>
#include <string>

#include "server/render/gl_context.h"

namespace sim4cv::render {
namespace {

class OsMesaContext final : public GlContext {
 public:
  OsMesaContext() {
    const int attributes[] = {OSMESA_FORMAT,
                              OSMESA_RGBA,
                              OSMESA_DEPTH_BITS,
                              0,
                              OSMESA_STENCIL_BITS,
                              0,
                              OSMESA_PROFILE,
                              OSMESA_CORE_PROFILE,
                              OSMESA_CONTEXT_MAJOR_VERSION,
                              3,
                              OSMESA_CONTEXT_MINOR_VERSION,
                              3,
                              0};
    context_ = OSMesaCreateContextAttribs(attributes, nullptr);
    if (context_ == nullptr) throw std::runtime_error("OSMesa: cannot create an OpenGL 3.3 core-profile context");
    MakeCurrent();
    // Read now: later another context may be current on this thread.
    const auto* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    renderer_name_ = name != nullptr ? name : "unknown";
  }

  ~OsMesaContext() override { OSMesaDestroyContext(context_); }
  OsMesaContext(const OsMesaContext&) = delete;
  OsMesaContext& operator=(const OsMesaContext&) = delete;

  void MakeCurrent() override {
    if (!OSMesaMakeCurrent(context_, surface_.data(), GL_UNSIGNED_BYTE, 1, 1)) {
      throw std::runtime_error("OSMesa: cannot make the context current");
    }
  }

  std::string RendererName() const override { return renderer_name_; }

 private:
  OSMesaContext context_ = nullptr;
  std::array<unsigned char, 4> surface_{};  // one RGBA pixel
  std::string renderer_name_;
};

}  // namespace

std::unique_ptr<GlContext> CreateGlContext() { return std::make_unique<OsMesaContext>(); }

}  // namespace sim4cv::render
