// Run logs after things go wrong: torn tails, damaged records at the end and
// in the middle, a full disk, and a writer killed with SIGKILL mid-run.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <random>
#include <system_error>
#include <thread>

#include "tests/support/no_warnings.h"
#include "tests/unit/runlog_test_support.h"

namespace sim4cv::runlog {
namespace {

using namespace testing;
constexpr int kRecords = 10;

std::vector<uint8_t> Prefix(const std::vector<uint8_t>& bytes, uint64_t size) {
  return {bytes.begin(), bytes.begin() + static_cast<long>(size)};
}

// What reading `path` gives: the records before it stopped and the ignored bytes.
std::pair<std::vector<FrameLogRecord>, uint64_t> ReadBack(const std::string& path) {
  RunLogReader reader(path);
  std::vector<FrameLogRecord> records = ReadAll(reader);
  return {std::move(records), reader.ignored_bytes()};
}

void ExpectRecords1To(const std::vector<FrameLogRecord>& records, int last) {
  ASSERT_EQ(records.size(), static_cast<std::size_t>(last));
  for (int i = 0; i < last; ++i) ExpectSameRecord(records[i], TestRecord(i + 1));
}

TEST(RunLogRecovery, CutAtEveryByteOfTheLastRecordKeepsTheOthers) {
  const std::string path = TempPath("log"), cut_path = TempPath("cut");
  const std::vector<uint64_t> offsets = WriteTestLog(path, kRecords);
  const std::vector<uint8_t> bytes = ReadBytes(path);
  const uint64_t last_start = offsets[kRecords - 1];
  for (uint64_t cut = last_start; cut < bytes.size(); ++cut) {
    WriteBytes(cut_path, Prefix(bytes, cut));
    const auto [records, ignored] = ReadBack(cut_path);
    ExpectRecords1To(records, kRecords - 1);
    EXPECT_EQ(ignored, cut - last_start) << "cut at " << cut;
  }
  const auto [records, ignored] = ReadBack(path);
  ExpectRecords1To(records, kRecords);
  EXPECT_EQ(ignored, 0u);
}

TEST(RunLogRecovery, AnyDamagedByteOfTheLastRecordDropsOnlyThatRecord) {
  const std::string path = TempPath("log"), bad_path = TempPath("bad");
  const std::vector<uint64_t> offsets = WriteTestLog(path, kRecords);
  const std::vector<uint8_t> bytes = ReadBytes(path);
  for (uint64_t at = offsets[kRecords - 1]; at < bytes.size(); ++at) {
    std::vector<uint8_t> damaged = bytes;
    damaged[at] ^= 0x40;
    WriteBytes(bad_path, damaged);
    const auto [records, ignored] = ReadBack(bad_path);
    ExpectRecords1To(records, kRecords - 1);
    EXPECT_EQ(ignored, bytes.size() - offsets[kRecords - 1]) << "byte " << at;
  }
}

TEST(RunLogRecovery, DamageInTheMiddleFollowedByValidDataThrows) {
  const std::string path = TempPath("log"), bad_path = TempPath("bad");
  const std::vector<uint64_t> offsets = WriteTestLog(path, kRecords);
  const std::vector<uint8_t> bytes = ReadBytes(path);
  // Record index 4 (frame id 5), every byte of it in turn: length, CRC, payload.
  for (uint64_t at = offsets[4]; at < offsets[5]; ++at) {
    std::vector<uint8_t> damaged = bytes;
    damaged[at] ^= 0x40;
    WriteBytes(bad_path, damaged);
    RunLogReader reader(bad_path);
    FrameLogRecord record;
    for (int i = 0; i < 4; ++i) ASSERT_TRUE(reader.Next(&record));
    try {
      reader.Next(&record);
      ADD_FAILURE() << "no exception for damage at byte " << at;
    } catch (const std::invalid_argument& e) {
      const std::string expected = bad_path + ": corrupt run log: record 4 at byte " + std::to_string(offsets[4]);
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("valid record follows at byte " + std::to_string(offsets[5])),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(RunLogRecovery, GarbageOrZerosAfterTheLastRecordAreIgnored) {
  const std::string path = TempPath("log"), bad_path = TempPath("bad");
  WriteTestLog(path, kRecords);
  const std::vector<uint8_t> bytes = ReadBytes(path);
  std::mt19937 random(7);
  std::vector<uint8_t> garbage(4096), zeros(4096, 0);
  for (uint8_t& b : garbage) b = static_cast<uint8_t>(random());
  for (const auto& tail : {garbage, zeros}) {
    std::vector<uint8_t> damaged = bytes;
    damaged.insert(damaged.end(), tail.begin(), tail.end());
    WriteBytes(bad_path, damaged);
    const auto [records, ignored] = ReadBack(bad_path);
    ExpectRecords1To(records, kRecords);
    EXPECT_EQ(ignored, tail.size());
  }
}

TEST(RunLogRecovery, ValidRecordsWithDecreasingFrameIdsThrow) {
  const std::string path = TempPath("log"), spliced_path = TempPath("spliced");
  const std::vector<uint64_t> offsets = WriteTestLog(path, 3);
  std::vector<uint8_t> bytes = ReadBytes(path);
  bytes.insert(bytes.end(), bytes.begin() + static_cast<long>(offsets[0]),
               bytes.begin() + static_cast<long>(offsets[1]));
  WriteBytes(spliced_path, bytes);  // frame 1 again after frame 3
  RunLogReader reader(spliced_path);
  FrameLogRecord record;
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(reader.Next(&record));
  EXPECT_THROW(reader.Next(&record), std::invalid_argument);
}

TEST(RunLogWriteErrors, DiskFullNamesThePathAndTheErrno) {
  if (::access("/dev/full", W_OK) != 0) GTEST_SKIP() << "no /dev/full";
  try {
    RunLogWriter writer("/dev/full", TestHeader());
    FAIL() << "no exception";
  } catch (const std::system_error& e) {
    EXPECT_EQ(e.code().value(), ENOSPC);
    EXPECT_NE(std::string(e.what()).find("run log /dev/full: write header"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(std::strerror(ENOSPC)), std::string::npos) << e.what();
  }
}

// Lowers this process's file-size limit (a stand-in for a full disk that
// leaves a partial write behind) and ignores SIGXFSZ, until destroyed.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    old_handler_ = ::signal(SIGXFSZ, SIG_IGN);
    ::getrlimit(RLIMIT_FSIZE, &old_limit_);
    rlimit limit = old_limit_;
    limit.rlim_cur = bytes;
    EXPECT_EQ(::setrlimit(RLIMIT_FSIZE, &limit), 0);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &old_limit_);
    ::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit old_limit_{};
  sighandler_t old_handler_;
};

TEST(RunLogWriteErrors, FailedAppendLeavesAReadableLogAndCanBeRetried) {
  const std::string path = TempPath("log");
  RunLogWriter writer(path, TestHeader());
  uint64_t next_id = 1;
  {
    const FileSizeLimit limit(writer.bytes_written() + 5000);
    try {
      for (;; ++next_id) writer.Append(TestRecord(next_id));
    } catch (const std::system_error& e) {
      EXPECT_EQ(e.code().value(), EFBIG);
      EXPECT_NE(std::string(e.what()).find("run log " + path + ": write record"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(writer.records_written(), next_id - 1);
  struct stat info {};
  ASSERT_EQ(::stat(path.c_str(), &info), 0);
  EXPECT_EQ(static_cast<uint64_t>(info.st_size), writer.bytes_written());  // the partial record was cut off
  writer.Append(TestRecord(next_id));                                      // space again: the retry works
  const auto [records, ignored] = ReadBack(path);
  ExpectRecords1To(records, static_cast<int>(next_id));
  EXPECT_EQ(ignored, 0u);
}

// A record of ~22 KB whose content follows from its frame id, so the crash
// test can check each record it reads back.
FrameLogRecord CrashRecord(uint64_t frame_id) {
  FrameLogRecord record;
  record.frame_id = frame_id;
  record.sim_time = static_cast<double>(frame_id) / 30.0;
  record.entities.resize(200);
  for (uint32_t i = 0; i < record.entities.size(); ++i) {
    record.entities[i].id = i + 1;
    record.entities[i].body.position = {static_cast<double>(frame_id), static_cast<double>(i), 0.5};
  }
  return record;
}

[[noreturn]] void WriteUntilKilled(const std::string& path) {
  try {
    RunLogWriter writer(path, TestHeader());
    for (uint64_t id = 1;; ++id) writer.Append(CrashRecord(id));
  } catch (...) {
  }
  ::_exit(1);  // only reached if writing failed
}

uint64_t FileSize(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 ? static_cast<uint64_t>(info.st_size) : 0;
}

TEST(RunLogCrash, SigkillMidRunLeavesEveryWholeRecordReadable) {
  const uint64_t record_bytes = 8 + 16 + 4 + 200 * 108 + 3 * 4;
  int torn = 0;
  for (int run = 0; run < 6; ++run) {
    const std::string path = TempPath("log" + std::to_string(run));
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) WriteUntilKilled(path);
    // Let it write a varying amount, so the kill falls at different points.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (FileSize(path) < (1u << 20) * (run + 1) && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    ASSERT_EQ(::kill(child, SIGKILL), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "the writer stopped by itself";

    RunLogReader reader(path);
    EXPECT_EQ(reader.header(), TestHeader());
    FrameLogRecord record;
    uint64_t count = 0;
    while (reader.Next(&record)) {
      ++count;
      ASSERT_EQ(record.frame_id, count);  // consecutive from 1: nothing lost before the tail
      ExpectSameRecord(record, CrashRecord(count));
    }
    EXPECT_GE(count, 40u);
    EXPECT_LT(reader.ignored_bytes(), record_bytes);  // at most one partial record
    torn += reader.ignored_bytes() > 0;
  }
  std::printf("%d of 6 kills left a partial record behind\n", torn);
}

}  // namespace
}  // namespace sim4cv::runlog
