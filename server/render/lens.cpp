#include "server/render/lens.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "server/render/projection.h"

namespace sim4cv::render {

LensMap MakeLensMap(const CameraView& view) {
  const CameraIntrinsics k = IntrinsicsOf(view);
  LensMap map;
  map.source.resize(2 * static_cast<std::size_t>(view.width) * view.height);
  // First the undistorted normalised point of every pixel centre, then the
  // widening that keeps the farthest of them half a pixel inside the render.
  double reach = 0.0;
  const double fold = effects::FoldRadius(view.effects);
  for (uint32_t row = 0; row < view.height; ++row) {
    for (uint32_t column = 0; column < view.width; ++column) {
      double x = 0, y = 0;
      const std::size_t i = 2 * (static_cast<std::size_t>(row) * view.width + column);
      if (!effects::Undistort(view.effects, (column + 0.5 - k.cx) / k.fx, (row + 0.5 - k.cy) / k.fy, x, y) ||
          std::hypot(x, y) >= fold) {
        map.source[i] = map.source[i + 1] = std::numeric_limits<float>::quiet_NaN();  // past the fold
        continue;
      }
      map.source[i] = static_cast<float>(x);
      map.source[i + 1] = static_cast<float>(y);
      reach = std::max({reach, std::abs(x) * k.fx / (k.cx - 0.5), std::abs(y) * k.fy / (k.cy - 0.5)});
    }
  }
  map.widening = static_cast<float>(reach);
  const double fx = k.fx / reach, fy = k.fy / reach;
  for (std::size_t i = 0; i < map.source.size(); i += 2) {
    if (std::isnan(map.source[i])) {
      map.source[i] = map.source[i + 1] = -1.0f;
      continue;
    }
    map.source[i] = static_cast<float>(map.source[i] * fx + k.cx);
    map.source[i + 1] = static_cast<float>(map.source[i + 1] * fy + k.cy);
  }
  return map;
}

float WidenedFov(float fov_y_deg, float widening) {
  const double half = 0.5 * fov_y_deg * std::numbers::pi / 180.0;
  return static_cast<float>(2.0 * std::atan(widening * std::tan(half)) * 180.0 / std::numbers::pi);
}

void DistortPixel(const CameraView& view, float widening, double px, double py, double& u, double& v) {
  const CameraIntrinsics k = IntrinsicsOf(view);
  double xd = 0, yd = 0;
  effects::Distort(view.effects, (px - k.cx) * widening / k.fx, (py - k.cy) * widening / k.fy, xd, yd);
  u = xd * k.fx + k.cx;
  v = yd * k.fy + k.cy;
}

}  // namespace sim4cv::render
