// Cuts one encoded Frame envelope (FrameEncoder's segments, no length prefix)
// into FrameChunk datagrams without copying it: each datagram is a small
// header this class encodes by hand (Envelope.frame_chunk's tag and length,
// the FrameChunk's scalar fields, then the tag and length of its `data`
// field) followed by slices of the segments, ready for sendmsg's iovec. The
// pixels go from the shared Frame straight to the kernel.
#pragma once

#include <sys/uio.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "server/transport/frame_encoding.h"

namespace sim4cv::transport {

class FrameChunker {
 public:
  // Worst-case header: 1 (Envelope tag) + 3 (FrameChunk length, < 2^21) +
  // 1+10 (frame_id) + 4 × (1+5) (chunk_index, chunk_count, frame_bytes,
  // offset) + 1+3 (data tag and length).
  static constexpr std::size_t kMaxHeaderBytes = 43;
  // Largest datagram a UDP/IPv4 socket can send.
  static constexpr std::size_t kMaxDatagramBytes = 65507;
  // Most segments FrameEncoder produces (its segment array's size).
  static constexpr std::size_t kMaxSegments = 2 * channels::kPixelChannelCount + 1;
  // iovecs one chunk needs at most: its header plus a slice of every segment.
  static constexpr std::size_t kMaxIovecs = 1 + kMaxSegments;

  using Header = std::array<uint8_t, kMaxHeaderBytes>;

  // Throws std::invalid_argument naming the value unless
  // kMaxHeaderBytes < max_datagram_bytes <= kMaxDatagramBytes.
  explicit FrameChunker(std::size_t max_datagram_bytes);

  // Plans the chunks of one encoded envelope of `total_bytes` (>= 1,
  // < 4 GiB) spread over `segments`, which must stay valid while chunks are
  // built. Allocates nothing.
  void Start(uint64_t frame_id, std::span<const Segment> segments, std::size_t total_bytes);

  uint64_t frame_id() const { return frame_id_; }
  uint32_t chunk_count() const { return chunk_count_; }
  std::size_t total_bytes() const { return total_bytes_; }

  // Encodes chunk `index` (< chunk_count()): its header into `header`, and
  // into `iov` the header followed by the data slices. Returns the number of
  // iovecs used (<= kMaxIovecs); their sizes add up to the datagram's size,
  // which never exceeds max_datagram_bytes.
  std::size_t Build(uint32_t index, Header& header, iovec* iov) const;

 private:
  std::size_t payload_bytes_;  // data bytes per chunk; the last chunk may carry fewer
  uint64_t frame_id_ = 0;
  uint32_t chunk_count_ = 0;
  std::size_t total_bytes_ = 0;
  std::array<Segment, kMaxSegments> segments_{};
  std::array<std::size_t, kMaxSegments + 1> segment_start_{};  // offset of each segment; [count] = total
  std::size_t segment_count_ = 0;
};

}  // namespace sim4cv::transport
