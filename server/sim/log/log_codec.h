// The byte layout of run logs (docs/logs.md): the file preamble, the framing
// of each record ([u32 length][u32 CRC-32][payload]) and the header and frame
// payloads. Shared by the writer, the reader and the tests; no I/O here.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "server/sim/log/run_log.h"

namespace sim4cv::runlog::codec {

inline constexpr std::size_t kPreambleBytes = 12;    // magic[8], u32 format version
inline constexpr std::size_t kFrameHeaderBytes = 8;  // u32 payload length, u32 CRC-32 of the payload
// frame id, sim time and four empty counts: the smallest frame payload.
inline constexpr std::size_t kMinRecordPayload = 8 + 8 + 4 * 4;

// Replaces `out` with the preamble and the framed header: the first bytes of a
// log. Throws std::invalid_argument if a string is longer than 65535 bytes or
// a list longer than a u32 count.
void EncodeFileStart(const RunLogHeader& header, std::vector<uint8_t>* out);

// Replaces `out` with one framed record. Reuses out's capacity: no allocation
// once `out` has held a record this large. Throws std::invalid_argument if the
// record exceeds kMaxRecordBytes.
void EncodeRecord(const FrameLogRecord& record, std::vector<uint8_t>* out);

// Payload decoders: false unless `payload` is exactly one well-formed payload.
// `out` keeps its lists' capacity.
bool DecodeHeader(std::span<const uint8_t> payload, RunLogHeader* out);
bool DecodeRecord(std::span<const uint8_t> payload, FrameLogRecord* out);

// One framed record at the start of `bytes` (which runs to the end of the file).
enum class FrameStatus {
  kOk,
  kTruncated,  // the frame header or the payload runs past the end
  kBadLength,  // length below `min_payload` or above kMaxRecordBytes
  kBadCrc,
};
struct FrameView {
  FrameStatus status = FrameStatus::kTruncated;
  std::span<const uint8_t> payload;  // when kOk
  std::size_t frame_bytes = 0;       // header + payload, when kOk
};
FrameView ReadFrame(std::span<const uint8_t> bytes, std::size_t min_payload);
const char* FrameStatusName(FrameStatus status);

}  // namespace sim4cv::runlog::codec
