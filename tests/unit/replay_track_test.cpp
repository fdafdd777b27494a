// ReplayTrack: logged poses by frame id, for replay and for drawing paths.
#include "server/sim/log/replay_track.h"

#include <gtest/gtest.h>

#include "tests/support/no_warnings.h"
#include "tests/unit/runlog_test_support.h"

namespace sim4cv::runlog {
namespace {

using namespace testing;

// Frames 10, 11, 12, 20, 21 (a gap, as when logging paused); entity 2 is
// missing from frame 12.
std::string WriteGappyLog() {
  const std::string path = TempPath("log");
  RunLogWriter writer(path, TestHeader());
  for (uint64_t id : {10, 11, 12, 20, 21}) {
    FrameLogRecord record = TestRecord(id, 3);
    record.entities.resize(2);
    record.entities[0].id = 1;
    record.entities[1].id = 2;
    record.entities[1].body.position = {static_cast<double>(id), -1.0, 15.0};
    if (id == 12) record.entities.pop_back();
    writer.Append(record);
  }
  return path;
}

TEST(ReplayTrack, FindsEveryLoggedPoseByFrameId) {
  const std::string path = WriteGappyLog();
  const ReplayTrack track = ReplayTrack::Load(path);
  EXPECT_EQ(track.header(), TestHeader());
  ASSERT_EQ(track.frame_count(), 5u);
  EXPECT_EQ(track.frame_id(0), 10u);
  EXPECT_EQ(track.frame_id(4), 21u);
  EXPECT_DOUBLE_EQ(track.sim_time(3), 20.0 / 30.0);
  EXPECT_EQ(track.IndexOf(20), std::optional<std::size_t>(3));
  EXPECT_EQ(track.IndexOf(13), std::nullopt);
  EXPECT_EQ(track.IndexOf(9), std::nullopt);
  EXPECT_EQ(track.IndexOf(22), std::nullopt);

  for (uint64_t id : {10, 11, 20, 21}) {
    const sim::BodyState* uav = track.Find(id, 2);
    ASSERT_NE(uav, nullptr) << id;
    EXPECT_EQ(uav->position, Eigen::Vector3d(static_cast<double>(id), -1.0, 15.0));
    // The car's pose is the one logged, bit for bit.
    ExpectSameBody(*track.Find(id, 1), TestRecord(id, 3).entities[0].body);
  }
  EXPECT_EQ(track.Find(12, 2), nullptr);  // not logged in that frame
  EXPECT_NE(track.Find(12, 1), nullptr);
  EXPECT_EQ(track.Find(15, 1), nullptr);  // no such frame
  EXPECT_EQ(track.Find(10, 9), nullptr);  // no such entity

  ASSERT_EQ(track.EntitiesAt(2).size(), 1u);
  ASSERT_EQ(track.EntitiesAt(3).size(), 2u);
  EXPECT_EQ(track.EntitiesAt(3)[1].id, 2u);

  const std::vector<Eigen::Vector3d> path_of_uav = track.PositionsOf(2);
  ASSERT_EQ(path_of_uav.size(), 4u);
  EXPECT_EQ(path_of_uav[2].x(), 20.0);
  EXPECT_TRUE(track.PositionsOf(7).empty());
}

TEST(ReplayTrack, DropsATornTailAndSaysSo) {
  const std::string path = WriteGappyLog();
  std::vector<uint8_t> bytes = ReadBytes(path);
  bytes.resize(bytes.size() - 3);
  WriteBytes(path, bytes);
  RunLogReader reader(path);
  const ReplayTrack track(reader);
  EXPECT_EQ(track.frame_count(), 4u);
  EXPECT_GT(track.ignored_bytes(), 0u);
  EXPECT_EQ(track.frame_id(3), 20u);
}

TEST(ReplayTrack, EmptyLogGivesAnEmptyTrack) {
  const std::string path = TempPath("log");
  { RunLogWriter writer(path, TestHeader()); }
  const ReplayTrack track = ReplayTrack::Load(path);
  EXPECT_TRUE(track.empty());
  EXPECT_EQ(track.IndexOf(0), std::nullopt);
  EXPECT_EQ(track.Find(0, 1), nullptr);
}

}  // namespace
}  // namespace sim4cv::runlog
