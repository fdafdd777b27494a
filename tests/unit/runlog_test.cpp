// Run logs: round trip, the byte layout of docs/logs.md, and the header's
// error messages.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <stdexcept>
#include <system_error>

#include "server/sim/log/crc32.h"
#include "server/sim/log/log_codec.h"
#include "sim4cv.pb.h"
#include "tests/support/no_warnings.h"
#include "tests/unit/runlog_test_support.h"

namespace sim4cv::runlog {
namespace {

using namespace testing;

uint32_t U32At(const std::vector<uint8_t>& bytes, std::size_t offset) {
  uint32_t value;
  std::memcpy(&value, bytes.data() + offset, sizeof value);
  return value;
}

void SetU32At(std::vector<uint8_t>& bytes, std::size_t offset, uint32_t value) {
  std::memcpy(bytes.data() + offset, &value, sizeof value);
}

// The header's payload starts after the preamble and its frame header.
constexpr std::size_t kHeaderPayloadAt = codec::kPreambleBytes + codec::kFrameHeaderBytes;

// Recomputes the header's CRC after a test has edited its payload.
void ResealHeader(std::vector<uint8_t>& bytes) {
  const uint32_t length = U32At(bytes, codec::kPreambleBytes);
  SetU32At(bytes, codec::kPreambleBytes + 4, Crc32({bytes.data() + kHeaderPayloadAt, length}));
}

// The message of the std::invalid_argument that opening `path` throws.
std::string OpenError(const std::string& path) {
  try {
    RunLogReader reader(path);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "opening " << path << " did not throw";
  return "";
}

TEST(Crc32, MatchesTheStandardCheckValue) {
  const std::string text = "123456789";
  const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(text.data()), text.size());
  EXPECT_EQ(Crc32(bytes), 0xCBF43926u);
  EXPECT_EQ(Crc32(bytes.subspan(4), Crc32(bytes.first(4))), 0xCBF43926u);  // chained
  EXPECT_EQ(Crc32({}), 0u);
}

TEST(RunLog, EnumValuesMatchTheProtocol) {
  EXPECT_EQ(kEntityKindCar, proto::ENTITY_KIND_CAR);
  EXPECT_EQ(kEntityKindUav, proto::ENTITY_KIND_UAV);
  EXPECT_EQ(kObjectClassCar, proto::OBJECT_CLASS_CAR);
  EXPECT_EQ(kObjectClassUav, proto::OBJECT_CLASS_UAV);
}

TEST(RunLog, RoundTripsHeaderAndManyRecordsBitExactly) {
  const std::string path = TempPath("log");
  constexpr int kRecords = 2000;
  {
    RunLogWriter writer(path, TestHeader());
    for (int i = 1; i <= kRecords; ++i) writer.Append(TestRecord(i, 5));
    EXPECT_EQ(writer.records_written(), static_cast<uint64_t>(kRecords));
    writer.Close();
  }
  RunLogReader reader(path);
  EXPECT_EQ(reader.header(), TestHeader());
  FrameLogRecord record;
  for (int i = 1; i <= kRecords; ++i) {
    ASSERT_TRUE(reader.Next(&record)) << "record " << i;
    ExpectSameRecord(record, TestRecord(i, 5));
  }
  EXPECT_FALSE(reader.Next(&record));
  EXPECT_FALSE(reader.Next(&record));  // stays at the end
  EXPECT_EQ(reader.records_read(), static_cast<uint64_t>(kRecords));
  EXPECT_EQ(reader.ignored_bytes(), 0u);
}

TEST(RunLog, HeadersWrittenBeforeConditionsExistedStillDecode) {
  RunLogHeader old = TestHeader();
  old.conditions.clear();
  std::vector<uint8_t> bytes;
  codec::EncodeFileStart(old, &bytes);
  // The payload after the preamble and its frame header, without the
  // trailing conditions string (a u16 length of 0): what older writers wrote.
  const std::span<const uint8_t> payload(bytes.data() + codec::kPreambleBytes + codec::kFrameHeaderBytes,
                                         bytes.size() - codec::kPreambleBytes - codec::kFrameHeaderBytes - sizeof(uint16_t));
  RunLogHeader decoded;
  ASSERT_TRUE(codec::DecodeHeader(payload, &decoded));
  EXPECT_EQ(decoded, old);
  EXPECT_EQ(decoded.conditions, "");
}

TEST(RunLog, KeepsAwkwardDoublesBitForBit) {
  FrameLogRecord awkward = TestRecord(7, 0);
  const double values[] = {-0.0, std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::infinity(),
                           -std::numeric_limits<double>::max(), std::nan("0x5a5a5")};
  sim::BodyState& body = awkward.entities.at(0).body;
  for (int i = 0; i < 3; ++i) body.position[i] = values[i];
  body.linear_velocity = {values[3], values[4], values[0]};
  body.orientation = Eigen::Quaterniond(values[4], values[0], values[1], values[2]);
  awkward.sim_time = values[4];
  const std::string path = TempPath("log");
  RunLogWriter(path, TestHeader()).Append(awkward);
  RunLogReader reader(path);
  FrameLogRecord record;
  ASSERT_TRUE(reader.Next(&record));
  ExpectSameRecord(record, awkward);
}

TEST(RunLog, FileStartsWithTheDocumentedPreambleAndFrames) {
  const std::string path = TempPath("log");
  FrameLogRecord one;  // one item of each list
  one.frame_id = 42;
  one.entities.resize(1);
  one.tracker_boxes.resize(1);
  one.ground_truth.resize(1);
  one.controls.resize(1);
  uint64_t header_end = 0;
  {
    RunLogWriter writer(path, TestHeader());
    header_end = writer.bytes_written();
    writer.Append(one);
  }
  const std::vector<uint8_t> bytes = ReadBytes(path);
  EXPECT_EQ(std::memcmp(bytes.data(), "S4CVLOG\0", 8), 0);
  EXPECT_EQ(U32At(bytes, 8), 1u);                              // format version
  EXPECT_EQ(header_end, kHeaderPayloadAt + U32At(bytes, 12));  // the header frame fills the gap
  EXPECT_EQ(U32At(bytes, kHeaderPayloadAt), kRecordVersion);   // first header field
  // docs/logs.md: 16 + (4 + 108) + (4 + 34) + (4 + 26) + (4 + 17) payload bytes.
  const uint32_t payload = 16 + (4 + 108) + (4 + 34) + (4 + 26) + (4 + 17);
  EXPECT_EQ(U32At(bytes, header_end), payload);
  EXPECT_EQ(U32At(bytes, header_end + 4), Crc32({bytes.data() + header_end + 8, payload}));
  EXPECT_EQ(bytes.size(), header_end + 8 + payload);
  uint64_t frame_id;
  std::memcpy(&frame_id, bytes.data() + header_end + 8, sizeof frame_id);
  EXPECT_EQ(frame_id, 42u);
}

TEST(RunLog, HeaderOnlyLogHasNoRecords) {
  const std::string path = TempPath("log");
  { RunLogWriter writer(path, TestHeader()); }
  RunLogReader reader(path);
  FrameLogRecord record;
  EXPECT_FALSE(reader.Next(&record));
  EXPECT_EQ(reader.records_read(), 0u);
  EXPECT_EQ(reader.ignored_bytes(), 0u);
}

TEST(RunLog, WriterStampsTheCreationTimeOnlyWhenUnset) {
  const std::string path = TempPath("log");
  RunLogHeader header = TestHeader();
  header.record_version = 99;  // the writer owns this field
  EXPECT_EQ(RunLogWriter(path, header).header().created_unix_ns, header.created_unix_ns);
  EXPECT_EQ(RunLogReader(path).header().record_version, kRecordVersion);
  header.created_unix_ns = 0;
  EXPECT_GT(RunLogWriter(path, header).header().created_unix_ns, 1'600'000'000'000'000'000);
}

TEST(RunLog, WriterRefusesFrameIdsThatDoNotIncrease) {
  const std::string path = TempPath("log");
  RunLogWriter writer(path, TestHeader());
  writer.Append(TestRecord(0));  // frame 0 may come first
  writer.Append(TestRecord(5));
  EXPECT_THROW(writer.Append(TestRecord(5)), std::invalid_argument);
  EXPECT_THROW(writer.Append(TestRecord(3)), std::invalid_argument);
  writer.Append(TestRecord(6));
  writer.Close();
  EXPECT_THROW(writer.Append(TestRecord(7)), std::invalid_argument);
  RunLogReader reader(path);
  EXPECT_EQ(ReadAll(reader).size(), 3u);
}

TEST(RunLog, WriterRefusesStringsTooLongToEncode) {
  RunLogHeader header = TestHeader();
  header.entities[1].name = std::string(70000, 'x');
  EXPECT_THROW(RunLogWriter(TempPath("log"), header), std::invalid_argument);
}

TEST(RunLogErrors, WrongMagicNamesThePathAndWhatItFound) {
  const std::string path = TempPath("not_a_log.png");
  WriteBytes(path, {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 0, 0, 0});
  const std::string message = OpenError(path);
  EXPECT_NE(message.find(path + ": not a sim4cv run log"), std::string::npos) << message;
  EXPECT_NE(message.find("\\x89PNG\\x0d\\x0a"), std::string::npos) << message;
}

TEST(RunLogErrors, TooShortAndEmptyFilesAreNotRunLogs) {
  const std::string path = TempPath("log");
  for (const std::vector<uint8_t>& bytes : {std::vector<uint8_t>{}, std::vector<uint8_t>{'S', '4', 'C'}}) {
    WriteBytes(path, bytes);
    EXPECT_NE(OpenError(path).find("not a sim4cv run log"), std::string::npos);
  }
}

TEST(RunLogErrors, UnsupportedFormatVersion) {
  const std::string path = TempPath("log");
  WriteTestLog(path, 3);
  std::vector<uint8_t> bytes = ReadBytes(path);
  SetU32At(bytes, 8, 2);
  WriteBytes(path, bytes);
  const std::string message = OpenError(path);
  EXPECT_NE(message.find(path + ": run log format version 2 is not supported (this build reads version 1)"),
            std::string::npos)
      << message;
}

TEST(RunLogErrors, UnsupportedRecordVersion) {
  const std::string path = TempPath("log");
  WriteTestLog(path, 3);
  std::vector<uint8_t> bytes = ReadBytes(path);
  SetU32At(bytes, kHeaderPayloadAt, 3);
  ResealHeader(bytes);
  WriteBytes(path, bytes);
  const std::string message = OpenError(path);
  EXPECT_NE(message.find(path + ": run log record layout version 3 is not supported"), std::string::npos) << message;
}

TEST(RunLogErrors, DamagedOrTruncatedHeader) {
  const std::string path = TempPath("log");
  WriteTestLog(path, 0);
  const std::vector<uint8_t> good = ReadBytes(path);
  std::vector<uint8_t> bytes = good;
  bytes[kHeaderPayloadAt + 20] ^= 0x01;
  WriteBytes(path, bytes);
  EXPECT_NE(OpenError(path).find(path + ": run log header is damaged (CRC mismatch"), std::string::npos);
  for (std::size_t size = codec::kPreambleBytes; size < good.size(); ++size) {
    WriteBytes(path, std::vector<uint8_t>(good.begin(), good.begin() + static_cast<long>(size)));
    EXPECT_NE(OpenError(path).find("header is damaged (runs past the end"), std::string::npos) << size;
  }
}

TEST(RunLogErrors, MissingFileNamesThePathAndTheErrno) {
  try {
    RunLogReader reader("/nonexistent/dir/run.s4log");
    FAIL() << "no exception";
  } catch (const std::system_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/run.s4log"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sim4cv::runlog
