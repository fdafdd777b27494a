// Appends frame records to a run log (docs/logs.md) from the sim thread.
//
// Each Append is one write() of one whole framed record straight to the file
// descriptor: nothing waits in user space, so a SIGKILL or a crash of the
// daemon loses at most the record being written, and the reader drops that
// torn tail. A kernel crash can lose more unless fsync_each_record is set.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "server/sim/log/run_log.h"

namespace sim4cv::runlog {

struct RunLogWriterOptions {
  // fsync after every record: survives power loss, costs a disk flush per
  // frame (milliseconds on most disks), so off by default.
  bool fsync_each_record = false;
};

class RunLogWriter {
 public:
  // Creates (or truncates) `path` and writes the header. Fills
  // created_unix_ns with the current time if it is 0 and record_version
  // with kRecordVersion. Throws std::system_error naming the path and the
  // errno text, or std::invalid_argument for a header too large to encode.
  RunLogWriter(const std::string& path, const RunLogHeader& header, RunLogWriterOptions options = {});
  // The same on a file the caller created and opened for writing with
  // O_APPEND (a client's StartLog, opened beneath --logs-dir); takes
  // ownership of `fd` (closed if the header cannot be written). `path` is
  // for messages.
  RunLogWriter(int fd, const std::string& path, const RunLogHeader& header, RunLogWriterOptions options = {});
  ~RunLogWriter();
  RunLogWriter(const RunLogWriter&) = delete;
  RunLogWriter& operator=(const RunLogWriter&) = delete;

  // Writes one record. frame_id must be greater than the previous record's
  // (std::invalid_argument otherwise). On a write error (disk full, file too
  // large) it cuts the file back to its last whole record, so the log stays
  // readable and a later Append may succeed, and throws std::system_error
  // naming the path and the errno text. Allocates nothing once the writer
  // has seen a record this large.
  void Append(const FrameLogRecord& record);

  // Closes the file (the destructor does too, but cannot report an error).
  void Close();

  const std::string& path() const { return path_; }
  const RunLogHeader& header() const { return header_; }
  uint64_t records_written() const { return records_written_; }
  uint64_t bytes_written() const { return bytes_written_; }  // the file's size, header included

 private:
  // Writes buffer_ at the end of the file, or restores the file and throws.
  void WriteBuffer(const char* what);

  std::string path_;
  RunLogHeader header_;
  RunLogWriterOptions options_;
  int fd_ = -1;
  std::vector<uint8_t> buffer_;  // one framed record, reused
  uint64_t records_written_ = 0;
  uint64_t bytes_written_ = 0;
  uint64_t last_frame_id_ = 0;
};

}  // namespace sim4cv::runlog
