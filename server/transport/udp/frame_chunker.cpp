#include "server/transport/udp/frame_chunker.h"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/wire_format_lite.h>

#include <algorithm>

#include "server/common/check.h"
#include "sim4cv.pb.h"

namespace sim4cv::transport {
namespace {

using google::protobuf::io::CodedOutputStream;
using google::protobuf::internal::WireFormatLite;

constexpr uint8_t Tag(int field, WireFormatLite::WireType type) {
  return static_cast<uint8_t>(WireFormatLite::MakeTag(field, type));
}
constexpr uint8_t kEnvelopeChunkTag = Tag(proto::Envelope::kFrameChunkFieldNumber, WireFormatLite::WIRETYPE_LENGTH_DELIMITED);
constexpr uint8_t kFrameIdTag = Tag(proto::FrameChunk::kFrameIdFieldNumber, WireFormatLite::WIRETYPE_VARINT);
constexpr uint8_t kChunkIndexTag = Tag(proto::FrameChunk::kChunkIndexFieldNumber, WireFormatLite::WIRETYPE_VARINT);
constexpr uint8_t kChunkCountTag = Tag(proto::FrameChunk::kChunkCountFieldNumber, WireFormatLite::WIRETYPE_VARINT);
constexpr uint8_t kFrameBytesTag = Tag(proto::FrameChunk::kFrameBytesFieldNumber, WireFormatLite::WIRETYPE_VARINT);
constexpr uint8_t kOffsetTag = Tag(proto::FrameChunk::kOffsetFieldNumber, WireFormatLite::WIRETYPE_VARINT);
constexpr uint8_t kDataTag = Tag(proto::FrameChunk::kDataFieldNumber, WireFormatLite::WIRETYPE_LENGTH_DELIMITED);
static_assert(proto::FrameChunk::kDataFieldNumber < 16, "one-byte tags are assumed by kMaxHeaderBytes");

std::size_t Size32(uint32_t value) { return CodedOutputStream::VarintSize32(value); }

}  // namespace

FrameChunker::FrameChunker(std::size_t max_datagram_bytes) : payload_bytes_(max_datagram_bytes - kMaxHeaderBytes) {
  SIM4CV_THROW_UNLESS(max_datagram_bytes > kMaxHeaderBytes && max_datagram_bytes <= kMaxDatagramBytes,
                      "UDP datagram size " << max_datagram_bytes << " must be in [" << kMaxHeaderBytes + 1 << ", "
                                           << kMaxDatagramBytes << "] (daemon flag --udp-datagram-bytes)");
}

void FrameChunker::Start(uint64_t frame_id, std::span<const Segment> segments, std::size_t total_bytes) {
  SIM4CV_DEMAND(segments.size() <= kMaxSegments);
  SIM4CV_DEMAND(total_bytes >= 1 && total_bytes <= UINT32_MAX);
  frame_id_ = frame_id;
  total_bytes_ = total_bytes;
  chunk_count_ = static_cast<uint32_t>((total_bytes + payload_bytes_ - 1) / payload_bytes_);
  segment_count_ = 0;
  std::size_t start = 0;
  for (const Segment& segment : segments) {
    if (segment.size == 0) continue;
    segment_start_[segment_count_] = start;
    segments_[segment_count_++] = segment;
    start += segment.size;
  }
  segment_start_[segment_count_] = start;
  SIM4CV_DEMAND(start == total_bytes);
}

std::size_t FrameChunker::Build(uint32_t index, Header& header, iovec* iov) const {
  SIM4CV_DEMAND(index < chunk_count_);
  const std::size_t offset = static_cast<std::size_t>(index) * payload_bytes_;
  const std::size_t size = std::min(payload_bytes_, total_bytes_ - offset);
  const auto offset32 = static_cast<uint32_t>(offset);
  const auto size32 = static_cast<uint32_t>(size);
  const auto total32 = static_cast<uint32_t>(total_bytes_);

  // FrameChunk's body: five scalar fields, then `data`'s tag, length and bytes.
  const std::size_t body = 1 + CodedOutputStream::VarintSize64(frame_id_) + 1 + Size32(index) + 1 + Size32(chunk_count_) +
                           1 + Size32(total32) + 1 + Size32(offset32) + 1 + Size32(size32) + size;
  uint8_t* p = header.data();
  *p++ = kEnvelopeChunkTag;
  p = CodedOutputStream::WriteVarint32ToArray(static_cast<uint32_t>(body), p);
  *p++ = kFrameIdTag;
  p = CodedOutputStream::WriteVarint64ToArray(frame_id_, p);
  *p++ = kChunkIndexTag;
  p = CodedOutputStream::WriteVarint32ToArray(index, p);
  *p++ = kChunkCountTag;
  p = CodedOutputStream::WriteVarint32ToArray(chunk_count_, p);
  *p++ = kFrameBytesTag;
  p = CodedOutputStream::WriteVarint32ToArray(total32, p);
  *p++ = kOffsetTag;
  p = CodedOutputStream::WriteVarint32ToArray(offset32, p);
  *p++ = kDataTag;
  p = CodedOutputStream::WriteVarint32ToArray(size32, p);
  SIM4CV_DEMAND(static_cast<std::size_t>(p - header.data()) <= kMaxHeaderBytes);

  std::size_t used = 0;
  iov[used++] = {header.data(), static_cast<std::size_t>(p - header.data())};
  // Slices of the segments covering [offset, offset + size).
  std::size_t segment = 0;
  while (segment_start_[segment + 1] <= offset) ++segment;
  std::size_t position = offset;
  const std::size_t end = offset + size;
  while (position < end) {
    const std::size_t within = position - segment_start_[segment];
    const std::size_t take = std::min(segments_[segment].size - within, end - position);
    // iovec's base is non-const by POSIX; sendmsg only reads it.
    iov[used++] = {const_cast<uint8_t*>(segments_[segment].data + within), take};
    position += take;
    ++segment;
  }
  return used;
}

}  // namespace sim4cv::transport
