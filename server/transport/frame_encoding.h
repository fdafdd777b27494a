// Encodes a Frame for one subscriber as a (length-prefixed) Envelope without
// copying pixels: the result is a short list of segments that alternate
// between small header bytes owned by the encoder and the shared frame's own
// pixel buffers, ready for one scatter-gather write. Protobuf allows a
// message's fields in any order, so the pixel-free part is serialised by
// protobuf and each Image's `data` field is framed by hand around it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "server/session/frame.h"
#include "sim4cv.pb.h"

namespace sim4cv::transport {

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

  std::span<const Segment> segments() const { return {segments_.data(), segment_count_}; }
  std::size_t total_size() const { return total_size_; }

 private:
  proto::Frame meta_;   // reused: everything but the pixels
  proto::Image image_;  // reused: one image's header fields
  std::string headers_;  // every non-pixel byte, in wire order
  std::array<Segment, 8> segments_{};
  std::size_t segment_count_ = 0;
  std::size_t total_size_ = 0;
};

}  // namespace sim4cv::transport
