// A rendered frame of one camera, built once by the sim thread and then
// shared read-only by every transport that delivers it.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "protocol/channels.h"
#include "server/render/ground_truth.h"
#include "server/render/object_catalog.h"
#include "server/render/projection.h"
#include "server/session/ref_pool.h"
#include "sim4cv.pb.h"

namespace sim4cv::session {

struct Frame {
  // The pixels of `channel` (a pixel channel this frame holds), or nullptr.
  const uint8_t* Pixels(int channel) const {
    const auto index = channels::IndexOf(channel);
    return index && channels::Has(channels, channel) ? planes[*index].data() : nullptr;
  }
  // Makes the frame hold pixel channel `channel`: sizes its plane for
  // width x height (a pooled plane allocates only when it grows) and returns
  // it as values of T (uint8_t, uint16_t or float; see the channel's element).
  template <typename T = uint8_t>
  std::span<T> Hold(int channel) {
    const std::size_t index = channels::IndexOf(channel).value();
    const std::size_t bytes = static_cast<std::size_t>(width) * height * channels::kPixelChannels[index].bytes_per_pixel;
    planes[index].resize(bytes);
    channels |= channels::Bit(channel);
    return {reinterpret_cast<T*>(planes[index].data()), bytes / sizeof(T)};
  }
  template <typename T = uint8_t>
  std::span<const T> Plane(int channel) const {
    const uint8_t* pixels = Pixels(channel);
    if (pixels == nullptr) return {};
    return {reinterpret_cast<const T*>(pixels), planes[*channels::IndexOf(channel)].size() / sizeof(T)};
  }

  uint64_t frame_id = 0;
  double sim_time = 0.0;
  uint32_t camera_index = 0;
  // The camera's name as the frame was rendered, so transports need not look
  // it up in a camera list that may change meanwhile. A pooled frame keeps the
  // string's capacity, so assigning a name no longer than before allocates nothing.
  std::string camera_name;
  uint32_t width = 0, height = 0;
  // Which pixel channels this frame holds (bit 1 << proto Channel): those
  // some subscriber of the camera asked for, MASK too when one wants BOXES.
  channels::ChannelSet channels = 0;
  // Plane i holds channel channels::kPixelChannels[i] in its wire layout
  // (width*height pixels, top row first) if `channels` has it; otherwise it
  // is stale. Pooled frames keep their capacity.
  std::array<std::vector<uint8_t>, channels::kPixelChannelCount> planes;
  std::vector<render::GroundTruthBox> boxes;
  render::CameraIntrinsics intrinsics;
  render::Pose camera_pose;  // OpenCV axes (x right, y down, z forward) -> world
  std::vector<render::ObjectGroundTruth> objects;  // ordered by instance id (ObjectCatalog::Fill)
  int64_t render_end_mono_ns = 0;
  proto::State state;  // entity poses at this frame (reused message)
};

// Where the renderer may write a frame's planes in place, one pointer per
// entry of channels::kPixelChannels (null: not there).
using PixelTargets = std::array<uint8_t*, channels::kPixelChannelCount>;

using FramePool = RefPool<Frame>;
using FrameRef = PoolRef<Frame>;

// The State snapshot every GetState is answered from, published each frame.
struct StateSnapshot {
  proto::State state;  // without last_tracker_output
  std::vector<proto::TrackerOutput> tracker_outputs;  // parallel to tracker_clients
  std::vector<uint32_t> tracker_clients;
};

using StatePool = RefPool<StateSnapshot>;
using StateRef = PoolRef<StateSnapshot>;

}  // namespace sim4cv::session
