// Encodes a Frame for one subscriber as a (length-prefixed) Envelope without
// copying pixels: the result is a short list of segments that alternate
// between small header bytes owned by the encoder and the shared frame's own
// pixel buffers, ready for one scatter-gather write. Protobuf allows a
// message's fields in any order, so the pixel-free part is serialised by
// protobuf and each Image's `data` field is framed by hand around it.
#pragma once

#include <google/protobuf/arena.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "server/session/client_session.h"
#include "server/session/frame.h"
#include "sim4cv.pb.h"

namespace sim4cv::transport {

// A Frame's fields but its images, as every transport sends them: with
// `with_boxes` (the subscription has CHANNEL_BOXES) its boxes, camera and
// objects; with `with_state` the entities' State; `dropped` is
// Frame.dropped_frames.
void FillFrameMeta(const session::Frame& frame, const std::string& camera_name, bool with_boxes, bool with_state,
                   uint64_t dropped, proto::Frame& meta);

struct Segment {
  const uint8_t* data = nullptr;
  std::size_t size = 0;
};

class FrameEncoder {
 public:
  // `subscription` gives the channels and their order; `dropped` goes into
  // Frame.dropped_frames. With `length_prefix`, the 4-byte TCP prefix leads.
  void Encode(const session::Frame& frame, const std::string& camera_name, const proto::Subscribed& subscription,
              bool with_state, uint64_t dropped, bool length_prefix);

  // The same for `session`'s subscription: its channels, state, drop count.
  void Encode(const session::Frame& frame, const session::ClientSession& session, bool length_prefix);

  std::span<const Segment> segments() const { return {segments_.data(), segment_count_}; }
  std::size_t total_size() const { return total_size_; }

 private:
  // An empty Frame on the arena, which is reset for it.
  proto::Frame& FreshMeta();

  // Clearing a heap message frees its sub-messages (the objects' positions,
  // the State), so the per-frame message lives on an arena instead, whose one
  // block grows to the largest frame seen: once warm, encoding allocates nothing.
  std::vector<char> arena_block_;
  std::optional<google::protobuf::Arena> arena_;
  proto::Image image_;   // reused: one image's header fields
  std::string headers_;  // every non-pixel byte, in wire order
  // A header before each image's pixels, then the tail.
  std::array<Segment, 2 * channels::kPixelChannelCount + 1> segments_{};
  std::size_t segment_count_ = 0;
  std::size_t total_size_ = 0;
};

}  // namespace sim4cv::transport
