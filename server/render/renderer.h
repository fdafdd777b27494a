// Draws a list of mesh instances from one camera into the pixel channels
// asked for (protocol/channels.h; one pass, multiple render targets), and
// measures how many pixels each labelled instance would cover if nothing
// occluded it.
// Needs a current GL context (see gl_context.h); owns only GL objects.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "server/render/look.h"
#include "server/render/render_types.h"

namespace sim4cv::render {

class Renderer {
 public:
  // Uploads every mesh once into vertex buffers. MeshId i is meshes[i].
  // max_width/max_height bound every later CameraView.
  Renderer(const std::vector<Mesh>& meshes, uint32_t max_width, uint32_t max_height);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Renders `items` seen by `camera` into the channels of `out` that are not
  // null (only those are drawn). Unless `unoccluded_pixels` is empty, for
  // every labelled item unoccluded_pixels[item.instance] receives the pixel
  // count of its silhouette rendered alone (entries of ids not drawn are left
  // untouched); the span must then have room for the largest instance id.
  // No heap allocation once each set of channels has been drawn once.
  void Render(const CameraView& camera, std::span<const DrawItem> items, const FrameBuffers& out,
              std::span<uint32_t> unoccluded_pixels);

  // How later frames' RGB is lit and shaded (look.h); the other channels
  // never depend on it. The default is LookOf(conditions::Conditions{}).
  void SetLook(const Look& look);
  // The street lanterns (world positions) that light the full look's RGB
  // when the look's lights are on: each frame the kMaxLamps nearest the
  // point 15 m ahead of the camera (each lamp costs every pixel).
  void SetLamps(std::vector<Eigen::Vector3f> lamps);
  static constexpr int kMaxLamps = 4;
  // The headlights of the cars that drive (SceneGraphics::headlights), set
  // each frame: with the look's lights on, the kMaxHeadlights nearest the
  // point 15 m ahead of the camera light the road. Copied; no allocation
  // once the number of cars stops growing.
  void SetHeadlights(std::span<const Headlight> headlights);
  static constexpr int kMaxHeadlights = 2;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim4cv::render
