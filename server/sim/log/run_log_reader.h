// Reads a run log (docs/logs.md) record by record.
//
// The end of a log is forgiving, the middle is not: a crash can leave at most
// one incomplete record at the end, so a damaged record (torn, bad length,
// CRC mismatch, payload that does not decode) with nothing valid after it is
// a torn tail: Next() stops cleanly and ignored_bytes() says how much was
// dropped. A damaged record followed by a valid record anywhere later is real
// corruption, and Next() throws naming the path and the byte offsets.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "server/sim/log/run_log.h"

namespace sim4cv::runlog {

class RunLogReader {
 public:
  // Maps the file and reads its header. Throws std::system_error naming the
  // path if it cannot be opened or mapped, and std::invalid_argument naming
  // the path for a file that is not a run log (wrong magic, too short), an
  // unsupported format or record version, or a damaged header. Sees the file
  // as it is now: records appended later are not read.
  explicit RunLogReader(const std::string& path);
  ~RunLogReader();
  RunLogReader(const RunLogReader&) = delete;
  RunLogReader& operator=(const RunLogReader&) = delete;

  const RunLogHeader& header() const { return header_; }

  // Decodes the next record into `record` (its lists keep their capacity, so
  // a reused record stops allocating). Returns false at the end of the log:
  // the file ended after a whole record, or only a damaged tail was left.
  // Throws std::invalid_argument on corruption followed by valid data, or if
  // the frame ids of two valid records do not increase.
  bool Next(FrameLogRecord* record);

  uint64_t records_read() const { return records_read_; }
  // Bytes of the damaged tail that were skipped; 0 until Next returns false,
  // and 0 for a log that ends cleanly.
  uint64_t ignored_bytes() const { return ignored_bytes_; }
  uint64_t file_size() const { return bytes_.size(); }
  const std::string& path() const { return path_; }

 private:
  void ReadHeader();
  // The offset of the first valid record after a damaged one at `offset`.
  std::optional<std::size_t> FindValidRecordAfter(std::size_t offset);

  std::string path_;
  std::span<const uint8_t> bytes_;  // the whole file, mapped read-only
  RunLogHeader header_;
  std::size_t offset_ = 0;  // of the next record
  bool at_end_ = false;
  uint64_t records_read_ = 0;
  uint64_t last_frame_id_ = 0;
  uint64_t ignored_bytes_ = 0;
};

}  // namespace sim4cv::runlog
