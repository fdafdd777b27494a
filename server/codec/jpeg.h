// JPEG compression as a camera effect: the RGB is encoded at a quality and
// decoded back in place (libjpeg-turbo, Debian's libjpeg62-turbo), so a
// client sees exactly the blocks and ringing a JPEG-streaming camera gives.
// Deterministic: the same pixels and quality give the same bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace sim4cv::codec {

// RGB8 to a baseline JPEG file in memory: the camera effect below, and the
// studio's WebSocket viewers (server/transport/http), which encode on their
// own thread, never the sim thread.
class JpegEncoder {
 public:
  // `rgb`: width*height RGB8 pixels, top row first; quality 1..100. The
  // bytes stay valid until the next call. Throws std::runtime_error with
  // libjpeg's message.
  std::span<const uint8_t> Encode(const uint8_t* rgb, uint32_t width, uint32_t height, int quality);

 private:
  std::vector<uint8_t> encoded_;  // reused: sized for the largest image seen
};

class JpegRoundTrip {
 public:
  // `rgb`: width*height RGB8 pixels, top row first; quality 1..100.
  // libjpeg allocates its own working memory per image: this effect is off
  // the zero-allocation path (docs/benchmarks.md gives its cost).
  void Apply(uint8_t* rgb, uint32_t width, uint32_t height, int quality);

 private:
  JpegEncoder encoder_;
};

}  // namespace sim4cv::codec
