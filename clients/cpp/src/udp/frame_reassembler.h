// Client side of UDP frame delivery: recognises FrameChunk datagrams without
// copying their data into a protobuf message, and puts frames back together.
// Depends on the protocol only.
//
// Rules (docs/protocol.md section 12): a frame is delivered only when every
// chunk 0..chunk_count-1 has arrived; a chunk of a newer frame makes an
// incomplete older frame count as dropped; chunks that are inconsistent,
// duplicated, or belong to a frame that is already finished or given up are
// ignored and counted; a frame id lower than the last finished one, starting
// at chunk 0, means the world restarted its frame ids (LoadMap, Reset).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace sim4cv::detail {

// One FrameChunk as found in a datagram; `data` points into the datagram.
struct ChunkView {
  uint64_t frame_id = 0;
  uint32_t chunk_index = 0;
  uint32_t chunk_count = 0;
  uint32_t frame_bytes = 0;
  uint32_t offset = 0;
  const uint8_t* data = nullptr;
  std::size_t size = 0;
};

enum class DatagramKind {
  kChunk,      // an Envelope carrying a FrameChunk: `chunk` is filled
  kOther,      // an Envelope carrying something else: parse it as an Envelope
  kMalformed,  // not a valid Envelope
};

// Looks at the top level of the Envelope in `datagram`. Field order and
// unknown fields are handled as protobuf does.
DatagramKind ClassifyDatagram(const uint8_t* datagram, std::size_t size, ChunkView& chunk);

class FrameReassembler {
 public:
  enum class Result {
    kPending,   // stored; the frame is not complete yet
    kComplete,  // the frame is complete: frame() holds its encoded Envelope
    kIgnored,   // nothing to deliver: the chunk was ignored (counted in chunks_ignored()),
                // or it completed a frame whose chunks do not tile it (counted as dropped)
  };

  // Frames announcing more than `max_frame_bytes` are ignored.
  explicit FrameReassembler(uint32_t max_frame_bytes) : max_frame_bytes_(max_frame_bytes) {}

  Result Add(const ChunkView& chunk);

  // The completed frame's encoded Envelope; valid until the next Add.
  std::string_view frame() const { return {buffer_.data(), frame_bytes_}; }

  // Forgets the frame in progress without counting it (a new connection).
  void Reset();

  uint64_t frames_completed() const { return frames_completed_; }
  uint64_t frames_dropped_incomplete() const { return frames_dropped_incomplete_; }
  uint64_t chunks_ignored() const { return chunks_ignored_; }

 private:
  Result Ignore() {
    ++chunks_ignored_;
    return Result::kIgnored;
  }
  void Abandon();

  uint32_t max_frame_bytes_;
  // The frame in progress.
  bool assembling_ = false;
  uint64_t frame_id_ = 0;
  uint32_t chunk_count_ = 0;
  uint32_t frame_bytes_ = 0;
  uint32_t chunks_received_ = 0;
  std::size_t bytes_received_ = 0;
  std::vector<bool> received_;
  std::string buffer_;  // grows only, so steady-state reassembly allocates nothing
  // Frames with ids up to this one are finished (complete or given up).
  uint64_t finished_up_to_ = 0;

  uint64_t frames_completed_ = 0;
  uint64_t frames_dropped_incomplete_ = 0;
  uint64_t chunks_ignored_ = 0;
};

}  // namespace sim4cv::detail
