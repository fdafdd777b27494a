// A Frame for a WebSocket viewer: one JSON text message (the Envelope with
// the Frame's ids, camera, boxes, objects, state and, per image, its channel,
// format, encoding and byte count, but no pixels), then one binary message
// holding every image's bytes in the order listed. Raw planes are sent from
// the shared frame without copying; RGB may be JPEG-encoded here, on the
// transport's thread (the sim thread never encodes for a viewer).
#pragma once

// clang-format off
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
// clang-format on

#include <boost/asio/buffer.hpp>
#include <string>
#include <vector>

#include "server/codec/jpeg.h"
#include "server/session/client_session.h"
#include "server/session/frame.h"
#include "sim4cv.pb.h"

namespace sim4cv::transport {

// How a viewer wants its images, from the WebSocket's URL (/ws?rgb=raw).
struct WsViewOptions {
  bool jpeg_rgb = true;   // RGB as JPEG (IMAGE_ENCODING_JPEG); false: raw RGB8
  int jpeg_quality = 80;  // 1..100
};

class WsFrameWriter {
 public:
  // Encodes `frame` for `session`'s subscription (its channels in order,
  // boxes, state, drop count). Throws std::runtime_error if JPEG fails.
  void Build(const session::Frame& frame, const session::ClientSession& session, const WsViewOptions& view);

  // The text message: {"frame": {...}}.
  const std::string& header() const { return header_; }
  // The binary message's pieces; they point into the frame and this writer,
  // valid while both live and until the next Build.
  const std::vector<boost::asio::const_buffer>& binary() const { return binary_; }
  std::size_t binary_bytes() const { return binary_bytes_; }

 private:
  proto::Envelope envelope_;  // reused
  std::string header_;
  codec::JpegEncoder jpeg_;
  std::vector<boost::asio::const_buffer> binary_;
  std::size_t binary_bytes_ = 0;
};

}  // namespace sim4cv::transport
