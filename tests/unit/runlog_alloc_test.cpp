// The run-log writer and reader allocate nothing per record once warm: the
// writer runs on the sim thread, whose steady state allocates nothing.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "tests/support/no_warnings.h"
#include "tests/unit/runlog_test_support.h"

#include "tests/support/allocation_counter.h"

namespace sim4cv::runlog {
namespace {

using namespace testing;
using sim4cv::testing::AllocationsIn;
constexpr uint64_t kRecords = 500;

TEST(RunLogAllocations, CounterWorks) {
  EXPECT_EQ(AllocationsIn([] { ::operator delete(::operator new(16)); }), 1u);
}

// Frame 1 with every list at its longest, so later records fit its capacity.
FrameLogRecord LargestRecord() {
  FrameLogRecord record = TestRecord(1, 5);
  record.entities.resize(6);
  record.tracker_boxes.resize(5);
  record.ground_truth.resize(5);
  record.controls.resize(5);
  return record;
}

TEST(RunLogAllocations, AppendAndNextAllocateNothingOnceWarm) {
  // Built beforehand: the sim thread refills one reused record.
  std::vector<FrameLogRecord> records;
  for (uint64_t id = 2; id <= kRecords; ++id) records.push_back(TestRecord(id, 5));
  const std::string path = TempPath("log");
  {
    RunLogWriter writer(path, TestHeader());
    writer.Append(LargestRecord());
    EXPECT_EQ(AllocationsIn([&] {
                for (const FrameLogRecord& record : records) writer.Append(record);
              }),
              0u);
  }
  RunLogReader reader(path);
  FrameLogRecord record;
  ASSERT_TRUE(reader.Next(&record));  // warms the record's lists
  uint64_t read = 0;
  EXPECT_EQ(AllocationsIn([&] {
              while (reader.Next(&record)) ++read;
            }),
            0u);
  EXPECT_EQ(read, kRecords - 1);
}

}  // namespace
}  // namespace sim4cv::runlog
