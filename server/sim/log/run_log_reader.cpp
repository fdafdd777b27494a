#include "server/sim/log/run_log_reader.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "server/common/check.h"
#include "server/common/regular_file.h"
#include "server/sim/log/log_codec.h"
#include "server/sim/log/sys_error.h"

namespace sim4cv::runlog {
namespace {

using detail::ThrowErrno;

// The first bytes of a file as C-escaped text, for "not a run log" messages.
std::string Printable(std::span<const uint8_t> bytes) {
  std::string text;
  for (uint8_t b : bytes) {
    if (std::isprint(b) && b != '\\') {
      text += static_cast<char>(b);
    } else {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", b);
      text += escaped;
    }
  }
  return text;
}

uint32_t ReadU32(std::span<const uint8_t> bytes, std::size_t offset) {
  uint32_t value;
  std::memcpy(&value, bytes.data() + offset, sizeof value);
  return value;
}

}  // namespace

RunLogReader::RunLogReader(const std::string& path) : path_(path) {
  // A FIFO or device is refused, never waited on (docs/reliability.md, finding 7).
  const int fd = OpenRegularFile(path, O_RDONLY, "run log");
  struct stat info {};
  if (::fstat(fd, &info) != 0) {
    const int error = errno;
    ::close(fd);
    ThrowErrno(error, path_, "fstat");
  }
  const auto size = static_cast<std::size_t>(info.st_size);
  // mmap refuses a length of 0; a file that short is refused below anyway.
  void* data = size == 0 ? nullptr : ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
  const int map_error = errno;
  ::close(fd);  // the mapping stays valid without the descriptor
  if (data == MAP_FAILED) ThrowErrno(map_error, path_, "mmap");
  bytes_ = {static_cast<const uint8_t*>(data), size};
  try {
    ReadHeader();
  } catch (...) {
    if (data != nullptr) ::munmap(data, size);
    throw;
  }
}

RunLogReader::~RunLogReader() {
  if (!bytes_.empty()) ::munmap(const_cast<uint8_t*>(bytes_.data()), bytes_.size());
}

void RunLogReader::ReadHeader() {
  using codec::kPreambleBytes;
  SIM4CV_THROW_UNLESS(bytes_.size() >= kPreambleBytes && std::memcmp(bytes_.data(), kMagic, sizeof kMagic) == 0,
                      path_ << ": not a sim4cv run log (starts with '"
                            << Printable(bytes_.first(std::min(bytes_.size(), sizeof kMagic)))
                            << "', expected 'S4CVLOG\\x00')");
  const uint32_t version = ReadU32(bytes_, sizeof kMagic);
  SIM4CV_THROW_UNLESS(version == kFormatVersion, path_ << ": run log format version " << version
                                                       << " is not supported (this build reads version "
                                                       << kFormatVersion << ")");
  // The header is framed like a record; it has no minimum size of its own.
  const codec::FrameView frame = codec::ReadFrame(bytes_.subspan(kPreambleBytes), 0);
  SIM4CV_THROW_UNLESS(frame.status == codec::FrameStatus::kOk, path_ << ": run log header is damaged ("
                                                                     << codec::FrameStatusName(frame.status)
                                                                     << ", file of " << bytes_.size() << " bytes)");
  SIM4CV_THROW_UNLESS(
      codec::DecodeHeader(frame.payload, &header_),
      path_ << ": run log header is malformed (its fields do not fill its " << frame.payload.size() << " bytes)");
  SIM4CV_THROW_UNLESS(header_.record_version == kRecordVersion,
                      path_ << ": run log record layout version " << header_.record_version
                            << " is not supported (this build reads version " << kRecordVersion << ")");
  offset_ = kPreambleBytes + frame.frame_bytes;
}

bool RunLogReader::Next(FrameLogRecord* record) {
  if (at_end_ || offset_ == bytes_.size()) {
    at_end_ = true;
    return false;
  }
  const codec::FrameView frame = codec::ReadFrame(bytes_.subspan(offset_), codec::kMinRecordPayload);
  const bool valid = frame.status == codec::FrameStatus::kOk && codec::DecodeRecord(frame.payload, record);
  if (!valid) {
    const char* problem =
        frame.status == codec::FrameStatus::kOk ? "payload does not decode" : codec::FrameStatusName(frame.status);
    const std::optional<std::size_t> next = FindValidRecordAfter(offset_);
    SIM4CV_THROW_UNLESS(!next, path_ << ": corrupt run log: record " << records_read_ << " at byte " << offset_
                                     << " is damaged (" << problem << ") but a valid record follows at byte " << *next);
    ignored_bytes_ = bytes_.size() - offset_;
    at_end_ = true;
    return false;
  }
  SIM4CV_THROW_UNLESS(records_read_ == 0 || record->frame_id > last_frame_id_,
                      path_ << ": run log record " << records_read_ << " at byte " << offset_ << " has frame id "
                            << record->frame_id << " after frame id " << last_frame_id_
                            << " (frame ids must increase)");
  last_frame_id_ = record->frame_id;
  ++records_read_;
  offset_ += frame.frame_bytes;
  return true;
}

std::optional<std::size_t> RunLogReader::FindValidRecordAfter(std::size_t offset) {
  // Try every byte offset: after damage nothing says where records start.
  // Cheap in practice, since a torn tail is at most one record long and most
  // offsets fail at the length check before any CRC is computed.
  FrameLogRecord scratch;
  for (std::size_t at = offset + 1; at + codec::kFrameHeaderBytes + codec::kMinRecordPayload <= bytes_.size(); ++at) {
    const codec::FrameView frame = codec::ReadFrame(bytes_.subspan(at), codec::kMinRecordPayload);
    if (frame.status == codec::FrameStatus::kOk && codec::DecodeRecord(frame.payload, &scratch)) return at;
  }
  return std::nullopt;
}

}  // namespace sim4cv::runlog
