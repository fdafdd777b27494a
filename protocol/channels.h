// The pixel channels, listed once. Every reader of channels — the daemon's
// render targets, read-back, frames, encoder, UDP chunking, the shm ring's
// slot layout and --shm-channels, subscribe validation, --help, and the C++
// clients' image accessors — iterates this table; nothing else lists them.
// How a channel is rendered lives next to the daemon's renderer, one file per
// channel (server/render/channels/), keyed by the same table.
// docs/architecture.md, "How to add a channel", gives the steps.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "shm_layout.h"  // relative to this file: in the source tree and installed alike
#include "sim4cv.pb.h"

namespace sim4cv::channels {

// X(ENUM, flag name, PixelFormat, ElementType, components, what it holds):
// one line per pixel channel; ENUM is the proto Channel value without its
// CHANNEL_ prefix. The order is the order of planes in a frame and in a shm slot.
#define SIM4CV_PIXEL_CHANNELS(X)                                                                                     \
  X(RGB, "rgb", RGB8, U8, 3, "8-bit colour image, gamma encoded")                                                   \
  X(DEPTH, "depth", DEPTH_F32, F32, 1, "distance along the optical axis in metres; +inf where nothing was hit")      \
  X(MASK, "mask", INSTANCE_U16, U16, 1, "instance id of labelled objects; 0 elsewhere")                             \
  X(SEMANTIC, "semantic", SEMANTIC_U8, U8, 1, "semantic class per pixel, Cityscapes trainIds (protocol.md)")        \
  X(NORMALS, "normals", NORMAL_F32X3, F32, 3, "camera-space unit surface normal, OpenCV axes; 0,0,0 for sky")       \
  X(FLOW, "flow", FLOW_F32X2, F32, 2, "optical flow from the camera's previous frame to this one, pixels")         \
  X(ALBEDO, "albedo", RGB8, U8, 3, "surface colour before any light, gamma 2; 0,0,0 for sky")

struct ChannelInfo {
  proto::Channel id;
  std::string_view name;  // in flags (--shm-channels), client helpers and docs
  proto::PixelFormat format;
  proto::ElementType element;
  uint32_t components;
  uint32_t bytes_per_pixel;
  std::string_view summary;
};

constexpr uint32_t ElementBytes(proto::ElementType element) {
  return element == proto::ELEMENT_TYPE_U8 ? 1 : element == proto::ELEMENT_TYPE_U16 ? 2 : 4;
}

#define SIM4CV_CHANNEL_INFO(ENUM, NAME, FORMAT, ELEMENT, COMPONENTS, SUMMARY)                                     \
  ChannelInfo{proto::CHANNEL_##ENUM, NAME, proto::PIXEL_FORMAT_##FORMAT, proto::ELEMENT_TYPE_##ELEMENT, COMPONENTS, \
              COMPONENTS * ElementBytes(proto::ELEMENT_TYPE_##ELEMENT), SUMMARY},
inline constexpr std::array kPixelChannels = {SIM4CV_PIXEL_CHANNELS(SIM4CV_CHANNEL_INFO)};
#undef SIM4CV_CHANNEL_INFO

inline constexpr std::size_t kPixelChannelCount = kPixelChannels.size();
// GL guarantees 8 colour attachments; the shm slot header has room for kShmMaxChannels records.
static_assert(kPixelChannelCount <= 8, "one colour attachment per pixel channel");
static_assert(kPixelChannelCount <= shm::kShmMaxChannels, "grow kShmMaxChannels (and bump kShmLayoutVersion)");

// A set of channels (pixel channels and BOXES): bit (1 << proto Channel value).
using ChannelSet = uint32_t;
constexpr ChannelSet Bit(int channel) { return 1u << static_cast<uint32_t>(channel); }
constexpr bool Has(ChannelSet set, int channel) { return (set & Bit(channel)) != 0; }

constexpr ChannelSet MakeAllPixels() {
  ChannelSet set = 0;
  for (const ChannelInfo& info : kPixelChannels) set |= Bit(info.id);
  return set;
}
inline constexpr ChannelSet kAllPixels = MakeAllPixels();
static_assert((kAllPixels & Bit(proto::CHANNEL_BOXES)) == 0, "BOXES carries no pixels");
static_assert(kAllPixels < (1u << 31), "channel numbers fit a 32-bit set");

// Position of a pixel channel in kPixelChannels (its plane index), or nullopt.
constexpr std::optional<std::size_t> IndexOf(int channel) {
  for (std::size_t i = 0; i < kPixelChannelCount; ++i) {
    if (kPixelChannels[i].id == channel) return i;
  }
  return std::nullopt;
}
constexpr const ChannelInfo* Find(int channel) {
  const auto index = IndexOf(channel);
  return index ? &kPixelChannels[*index] : nullptr;
}
// The pixel channel named `name` ("depth"), or nullptr.
constexpr const ChannelInfo* FindByName(std::string_view name) {
  for (const ChannelInfo& info : kPixelChannels) {
    if (info.name == name) return &info;
  }
  return nullptr;
}

// Every channel a Subscribe may name: the pixel channels and BOXES.
constexpr bool Subscribable(int channel) { return Find(channel) != nullptr || channel == proto::CHANNEL_BOXES; }
inline constexpr int kSubscribableCount = static_cast<int>(kPixelChannelCount) + 1;

// "rgb,depth": the names of the pixel channels in `set`, in table order.
inline std::string Names(ChannelSet set) {
  std::string names;
  for (const ChannelInfo& info : kPixelChannels) {
    if (Has(set, info.id)) names.append(names.empty() ? "" : ",").append(info.name);
  }
  return names;
}

// "1 (RGB), 2 (DEPTH), ... and 4 (BOXES)": for messages that list what is valid.
std::string ValidList();

}  // namespace sim4cv::channels
