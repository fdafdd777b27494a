// Lens distortion (OpenCV's radial-tangential model, protocol/effects.h) as
// a remap: the scene is rendered through a pinhole camera whose view is
// widened just enough to cover what the distorted lens sees, and every pixel
// of the distorted image looks up where in that render it comes from. Pure
// CPU math, so it is tested without GL.
#pragma once

#include <cstdint>
#include <vector>

#include "protocol/effects.h"
#include "server/render/render_types.h"

namespace sim4cv::render {

struct LensMap {
  // The pinhole render's focal length is the camera's divided by this (its
  // tan(fov/2) is this times the camera's): > 1 when the lens sees more.
  float widening = 1.0f;
  // Per pixel of the distorted image, top row first: the continuous pixel
  // position (column, row; centres at +0.5) in the pinhole render that it
  // shows, or (-1, -1) past the lens's fold (effects::FoldRadius).
  std::vector<float> source;  // 2 * width * height
};

// For `view` with its effects' lens. Every source position lies at least
// half a pixel inside the render, so nearest and bilinear lookups stay in it.
LensMap MakeLensMap(const CameraView& view);

// The field of view (degrees, vertical) of the pinhole render for a camera of
// `fov_y_deg` and its lens map's widening.
float WidenedFov(float fov_y_deg, float widening);

// Where a point of the widened pinhole render (pixels) lands in the
// distorted image of `view` (pixels).
void DistortPixel(const CameraView& view, float widening, double px, double py, double& u, double& v);

}  // namespace sim4cv::render
