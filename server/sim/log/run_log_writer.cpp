#include "server/sim/log/run_log_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>

#include "server/common/check.h"
#include "server/common/regular_file.h"
#include "server/sim/log/log_codec.h"
#include "server/sim/log/sys_error.h"

namespace sim4cv::runlog {
namespace {

using detail::ThrowErrno;

int64_t NowUnixNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

RunLogWriter::RunLogWriter(const std::string& path, const RunLogHeader& header, RunLogWriterOptions options)
    // O_APPEND: after a failed write is cut off by ftruncate, the next write
    // lands at the new end, not at the old offset past a hole.
    // A FIFO or device is refused, never waited on (docs/reliability.md, finding 7).
    : RunLogWriter(OpenRegularFile(path, O_WRONLY | O_CREAT | O_TRUNC | O_APPEND, "run log",
                                   FileKinds::kRegularOrCharacterDevice),
                   path, header, options) {}

RunLogWriter::RunLogWriter(int fd, const std::string& path, const RunLogHeader& header, RunLogWriterOptions options)
    : path_(path), header_(header), options_(options), fd_(fd) {
  header_.record_version = kRecordVersion;
  if (header_.created_unix_ns == 0) header_.created_unix_ns = NowUnixNs();
  try {
    codec::EncodeFileStart(header_, &buffer_);
    WriteBuffer("write header");
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

RunLogWriter::~RunLogWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void RunLogWriter::Append(const FrameLogRecord& record) {
  SIM4CV_THROW_UNLESS(fd_ >= 0, "run log " << path_ << ": Append after Close");
  SIM4CV_THROW_UNLESS(records_written_ == 0 || record.frame_id > last_frame_id_,
                      "run log " << path_ << ": frame id " << record.frame_id << " after frame id " << last_frame_id_
                                 << " (frame ids must increase)");
  codec::EncodeRecord(record, &buffer_);
  WriteBuffer("write record");
  ++records_written_;
  last_frame_id_ = record.frame_id;
}

void RunLogWriter::Close() {
  if (fd_ < 0) return;
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) ThrowErrno(errno, path_, "close");
}

void RunLogWriter::WriteBuffer(const char* what) {
  // One write() call for the whole record in all but the disk-full case,
  // where the loop's next write reports the error.
  const uint8_t* data = buffer_.data();
  std::size_t left = buffer_.size();
  while (left > 0) {
    const ssize_t written = ::write(fd_, data, left);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) {
      const int error = written < 0 ? errno : EIO;
      // Drop whatever part of the record reached the file, so the log still
      // ends on a whole record. Best effort: if this fails too, the reader
      // treats the partial record as a torn tail.
      [[maybe_unused]] const int ignored = ::ftruncate(fd_, static_cast<off_t>(bytes_written_));
      ThrowErrno(error, path_, what);
    }
    data += written;
    left -= static_cast<std::size_t>(written);
  }
  bytes_written_ += buffer_.size();
  if (options_.fsync_each_record && ::fdatasync(fd_) != 0) ThrowErrno(errno, path_, "fdatasync");
}

}  // namespace sim4cv::runlog
