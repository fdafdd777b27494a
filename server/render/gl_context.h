// The one place that knows how an OpenGL context is made. The Renderer only
// uses whatever context is current, so a new backend (EGL, GLX) is one new
// file implementing GlContext, and no caller changes.
#pragma once

#include <memory>
#include <string>

namespace sim4cv::render {

class GlContext {
 public:
  virtual ~GlContext() = default;
  // Makes this context current on the calling thread.
  virtual void MakeCurrent() = 0;
  // GL_RENDERER of the context, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
  virtual std::string RendererName() const = 0;
};

// An OpenGL 3.3+ core-profile offscreen context from the backend this build
// uses (OSMesa's llvmpipe today, osmesa_context.cpp; an EGL backend would
// define this function in its own file instead). Throws std::runtime_error
// if the backend cannot create one.
std::unique_ptr<GlContext> CreateGlContext();

}  // namespace sim4cv::render
