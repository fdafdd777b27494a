// Pixel buffers for tests that call render::Renderer directly: one typed
// vector per channel of protocol/channels.h, and the FrameBuffers that point
// at those of a chosen set.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "protocol/channels.h"
#include "server/render/render_types.h"

namespace sim4cv::testing {

struct RenderedFrame {
  uint32_t width, height;
  std::vector<uint8_t> rgb;       // 3 per pixel
  std::vector<float> depth;       // 1 per pixel
  std::vector<uint16_t> mask;     // 1 per pixel
  std::vector<uint8_t> semantic;  // 1 per pixel
  std::vector<float> normals;     // 3 per pixel
  std::vector<float> flow;        // 2 per pixel
  std::vector<uint8_t> albedo;    // 3 per pixel

  RenderedFrame(uint32_t w, uint32_t h)
      : width(w),
        height(h),
        rgb(size_t{w} * h * 3),
        depth(size_t{w} * h),
        mask(size_t{w} * h),
        semantic(size_t{w} * h),
        normals(size_t{w} * h * 3),
        flow(size_t{w} * h * 2),
        albedo(size_t{w} * h * 3) {}

  // The buffers of the channels in `set` (RGB, depth and mask by default).
  render::FrameBuffers Buffers(channels::ChannelSet set = channels::Bit(proto::CHANNEL_RGB) |
                                                          channels::Bit(proto::CHANNEL_DEPTH) |
                                                          channels::Bit(proto::CHANNEL_MASK)) {
    render::FrameBuffers buffers{};
    const auto put = [&](proto::Channel channel, void* data) {
      if (channels::Has(set, channel)) buffers[*channels::IndexOf(channel)] = static_cast<uint8_t*>(data);
    };
    put(proto::CHANNEL_RGB, rgb.data());
    put(proto::CHANNEL_DEPTH, depth.data());
    put(proto::CHANNEL_MASK, mask.data());
    put(proto::CHANNEL_SEMANTIC, semantic.data());
    put(proto::CHANNEL_NORMALS, normals.data());
    put(proto::CHANNEL_FLOW, flow.data());
    put(proto::CHANNEL_ALBEDO, albedo.data());
    return buffers;
  }
  size_t At(uint32_t x, uint32_t y) const { return size_t{y} * width + x; }
  uint32_t Count(render::InstanceId id) const {
    return static_cast<uint32_t>(std::count(mask.begin(), mask.end(), id));
  }
};

}  // namespace sim4cv::testing
