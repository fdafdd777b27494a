#include "frame_reassembler.h"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/wire_format_lite.h>

#include <cstring>

#include "sim4cv.pb.h"

namespace sim4cv::detail {
namespace {

using google::protobuf::io::CodedInputStream;
using google::protobuf::internal::WireFormatLite;

// The Envelope's oneof members are fields 1 .. kLastKindField.
constexpr int kLastKindField = proto::Envelope::kStatsFieldNumber;

// Reads one length-delimited field's bounds; false if it overruns.
bool ReadBytes(CodedInputStream& input, const uint8_t* base, const uint8_t*& data, std::size_t& size) {
  uint32_t length = 0;
  if (!input.ReadVarint32(&length)) return false;
  const int position = input.CurrentPosition();
  if (!input.Skip(static_cast<int>(length))) return false;
  data = base + position;
  size = length;
  return true;
}

bool ParseChunk(const uint8_t* body, std::size_t size, ChunkView& chunk) {
  chunk = ChunkView{};
  CodedInputStream input(body, static_cast<int>(size));
  while (const uint32_t tag = input.ReadTag()) {
    const int field = WireFormatLite::GetTagFieldNumber(tag);
    const auto type = WireFormatLite::GetTagWireType(tag);
    if (field == 0) return false;
    if (type == WireFormatLite::WIRETYPE_VARINT && field >= 1 && field <= 5) {
      uint64_t value = 0;
      if (!input.ReadVarint64(&value)) return false;
      switch (field) {
        case proto::FrameChunk::kFrameIdFieldNumber: chunk.frame_id = value; break;
        case proto::FrameChunk::kChunkIndexFieldNumber: chunk.chunk_index = static_cast<uint32_t>(value); break;
        case proto::FrameChunk::kChunkCountFieldNumber: chunk.chunk_count = static_cast<uint32_t>(value); break;
        case proto::FrameChunk::kFrameBytesFieldNumber: chunk.frame_bytes = static_cast<uint32_t>(value); break;
        default: chunk.offset = static_cast<uint32_t>(value); break;
      }
    } else if (type == WireFormatLite::WIRETYPE_LENGTH_DELIMITED && field == proto::FrameChunk::kDataFieldNumber) {
      if (!ReadBytes(input, body, chunk.data, chunk.size)) return false;
    } else if (!WireFormatLite::SkipField(&input, tag)) {
      return false;
    }
  }
  return input.ConsumedEntireMessage();
}

}  // namespace

DatagramKind ClassifyDatagram(const uint8_t* datagram, std::size_t size, ChunkView& chunk) {
  CodedInputStream input(datagram, static_cast<int>(size));
  int last_kind = 0;  // the oneof member set last wins, as in protobuf
  const uint8_t* body = nullptr;
  std::size_t body_size = 0;
  while (const uint32_t tag = input.ReadTag()) {
    const int field = WireFormatLite::GetTagFieldNumber(tag);
    if (field == 0) return DatagramKind::kMalformed;
    if (field == proto::Envelope::kFrameChunkFieldNumber &&
        WireFormatLite::GetTagWireType(tag) == WireFormatLite::WIRETYPE_LENGTH_DELIMITED) {
      if (!ReadBytes(input, datagram, body, body_size)) return DatagramKind::kMalformed;
      last_kind = field;
      continue;
    }
    if (field <= kLastKindField) last_kind = field;
    if (!WireFormatLite::SkipField(&input, tag)) return DatagramKind::kMalformed;
  }
  if (!input.ConsumedEntireMessage()) return DatagramKind::kMalformed;
  if (last_kind != proto::Envelope::kFrameChunkFieldNumber) return DatagramKind::kOther;
  return ParseChunk(body, body_size, chunk) ? DatagramKind::kChunk : DatagramKind::kMalformed;
}

FrameReassembler::Result FrameReassembler::Add(const ChunkView& chunk) {
  // A chunk that contradicts itself can belong to no frame.
  if (chunk.chunk_count == 0 || chunk.chunk_index >= chunk.chunk_count || chunk.frame_bytes == 0 ||
      chunk.frame_bytes > max_frame_bytes_ || chunk.chunk_count > chunk.frame_bytes || chunk.size == 0 ||
      chunk.offset > chunk.frame_bytes || chunk.size > chunk.frame_bytes - chunk.offset) {
    return Ignore();
  }
  // The first chunk of a frame older than the last finished one, with no
  // frame in progress: the world's frame ids started again (LoadMap, Reset:
  // docs/protocol.md 10), since the daemon sends a frame's chunks in order
  // and only after the previous frame's. Without this, a UDP client stops
  // receiving frames after another client loads a map (found by the soak).
  if (!assembling_ && chunk.chunk_index == 0 && chunk.frame_id < finished_up_to_) finished_up_to_ = 0;
  // Already finished (complete, or overtaken and given up), or a late chunk
  // of a frame older than the one in progress.
  if (chunk.frame_id <= finished_up_to_ || (assembling_ && chunk.frame_id < frame_id_)) return Ignore();
  if (assembling_ && chunk.frame_id > frame_id_) Abandon();  // a newer frame overtakes
  if (!assembling_) {
    assembling_ = true;
    frame_id_ = chunk.frame_id;
    chunk_count_ = chunk.chunk_count;
    frame_bytes_ = chunk.frame_bytes;
    chunks_received_ = 0;
    bytes_received_ = 0;
    received_.assign(chunk_count_, false);
    if (buffer_.size() < frame_bytes_) buffer_.resize(frame_bytes_);
  }
  if (chunk.chunk_count != chunk_count_ || chunk.frame_bytes != frame_bytes_ || received_[chunk.chunk_index]) {
    return Ignore();  // inconsistent with the frame's other chunks, or a duplicate
  }
  std::memcpy(buffer_.data() + chunk.offset, chunk.data, chunk.size);
  received_[chunk.chunk_index] = true;
  ++chunks_received_;
  bytes_received_ += chunk.size;
  if (chunks_received_ < chunk_count_) return Result::kPending;
  assembling_ = false;
  finished_up_to_ = frame_id_;
  if (bytes_received_ != frame_bytes_) {  // every chunk came, but they do not tile the frame
    ++frames_dropped_incomplete_;
    return Result::kIgnored;
  }
  ++frames_completed_;
  return Result::kComplete;
}

void FrameReassembler::Abandon() {
  ++frames_dropped_incomplete_;
  finished_up_to_ = frame_id_;
  assembling_ = false;
}

void FrameReassembler::Reset() {
  assembling_ = false;
  finished_up_to_ = 0;
}

}  // namespace sim4cv::detail
