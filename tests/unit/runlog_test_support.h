// Helpers shared by the run-log tests: a typical header, records with varied
// contents and awkward doubles, bit-exact comparison, and file plumbing.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "server/sim/log/run_log.h"
#include "server/sim/log/run_log_reader.h"
#include "server/sim/log/run_log_writer.h"

namespace sim4cv::runlog::testing {

inline RunLogHeader TestHeader() {
  RunLogHeader header;
  header.created_unix_ns = 1'700'000'000'123'456'789;
  header.creator = "sim4cv tests";
  header.label = "MOSSE_CA";
  header.scene_name = "tracking_easy_desert";
  header.map_path = "scenes/tracking/easy_desert.map";
  header.physics_hz = 240.0;
  header.frame_hz = 30.0;
  header.seed = 0xDEADBEEFCAFEull;
  header.conditions = "rain at 15.00 h, full quality";
  header.entities = {{1, "car", kEntityKindCar, kObjectClassCar},
                     {2, "uav", kEntityKindUav, kObjectClassUav},
                     {3, "uav_b", kEntityKindUav, kObjectClassUav}};
  header.cameras = {{"uav_camera", 2, 320, 180}, {"uav_b_camera", 3, 320, 180}};
  return header;
}

// A value per (frame, slot) that covers signs, fractions and large magnitudes.
inline double Wiggle(uint64_t frame, int slot) {
  return std::sin(0.37 * static_cast<double>(frame) + slot) * std::pow(10.0, slot % 7 - 3);
}

// A record whose list lengths vary with the frame id (0 to `max_items`).
inline FrameLogRecord TestRecord(uint64_t frame_id, int max_items = 3) {
  FrameLogRecord record;
  record.frame_id = frame_id;
  record.sim_time = static_cast<double>(frame_id) / 30.0;
  const auto items = [&](int salt) { return static_cast<int>((frame_id + salt) % (max_items + 1)); };
  for (int i = 0; i <= items(0); ++i) {  // at least one entity
    EntityLog entity;
    entity.id = static_cast<uint32_t>(i + 1);
    entity.body.position = {Wiggle(frame_id, i), Wiggle(frame_id, i + 1), Wiggle(frame_id, i + 2)};
    entity.body.orientation = Eigen::Quaterniond(Wiggle(frame_id, 3), 0.1, -0.2, Wiggle(frame_id, 4)).normalized();
    entity.body.linear_velocity = {Wiggle(frame_id, 5), -1e-300, 1e300};
    entity.body.angular_velocity = {Wiggle(frame_id, 6), 0.0, -0.0};
    record.entities.push_back(entity);
  }
  for (int i = 0; i < items(1); ++i) {
    TrackerBoxLog box;
    box.camera = static_cast<uint16_t>(i % 2);
    box.box = {static_cast<uint32_t>(i + 1), frame_id - 1, 10.5f + i, 20.25f, 30.0f, 40.0f, 0.5f};
    record.tracker_boxes.push_back(box);
  }
  for (int i = 0; i < items(2); ++i) {
    record.ground_truth.push_back({static_cast<uint16_t>(i % 2), 1, 11u + i, 21, 29, 39, 0.875f});
  }
  for (int i = 0; i < items(3); ++i) {
    record.controls.push_back({1, {0.25f * i, 0.5f, 0.0f, (frame_id + i) % 2 == 0}});
  }
  return record;
}

template <typename T>
bool SameBits(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

inline void ExpectSameBody(const sim::BodyState& a, const sim::BodyState& b) {
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(SameBits(a.position[i], b.position[i]));
    EXPECT_TRUE(SameBits(a.linear_velocity[i], b.linear_velocity[i]));
    EXPECT_TRUE(SameBits(a.angular_velocity[i], b.angular_velocity[i]));
  }
  EXPECT_TRUE(SameBits(a.orientation.coeffs(), b.orientation.coeffs()));
}

// Every field bit for bit, so -0.0, NaN payloads and denormals count.
inline void ExpectSameRecord(const FrameLogRecord& a, const FrameLogRecord& b) {
  EXPECT_EQ(a.frame_id, b.frame_id);
  EXPECT_TRUE(SameBits(a.sim_time, b.sim_time));
  ASSERT_EQ(a.entities.size(), b.entities.size());
  for (std::size_t i = 0; i < a.entities.size(); ++i) {
    EXPECT_EQ(a.entities[i].id, b.entities[i].id);
    ExpectSameBody(a.entities[i].body, b.entities[i].body);
  }
  ASSERT_EQ(a.tracker_boxes.size(), b.tracker_boxes.size());
  for (std::size_t i = 0; i < a.tracker_boxes.size(); ++i) {
    const auto &x = a.tracker_boxes[i], &y = b.tracker_boxes[i];
    EXPECT_EQ(x.camera, y.camera);
    EXPECT_EQ(x.box.client_id, y.box.client_id);
    EXPECT_EQ(x.box.frame_id, y.box.frame_id);
    for (auto field : {&sim::TrackerReport::x, &sim::TrackerReport::y, &sim::TrackerReport::width,
                       &sim::TrackerReport::height, &sim::TrackerReport::confidence}) {
      EXPECT_TRUE(SameBits(x.box.*field, y.box.*field));
    }
  }
  ASSERT_EQ(a.ground_truth.size(), b.ground_truth.size());
  for (std::size_t i = 0; i < a.ground_truth.size(); ++i) {
    const auto &x = a.ground_truth[i], &y = b.ground_truth[i];
    EXPECT_EQ(x.camera, y.camera);
    EXPECT_EQ(x.object_id, y.object_id);
    EXPECT_EQ(x.x, y.x);
    EXPECT_EQ(x.y, y.y);
    EXPECT_EQ(x.width, y.width);
    EXPECT_EQ(x.height, y.height);
    EXPECT_TRUE(SameBits(x.visibility, y.visibility));
  }
  ASSERT_EQ(a.controls.size(), b.controls.size());
  for (std::size_t i = 0; i < a.controls.size(); ++i) {
    const auto &x = a.controls[i], &y = b.controls[i];
    EXPECT_EQ(x.entity_id, y.entity_id);
    EXPECT_TRUE(SameBits(x.command.steering, y.command.steering));
    EXPECT_TRUE(SameBits(x.command.throttle, y.command.throttle));
    EXPECT_TRUE(SameBits(x.command.brake, y.command.brake));
    EXPECT_EQ(x.command.manual, y.command.manual);
  }
}

// This test program's scratch directory, removed when the program ends.
inline std::filesystem::path ScratchDir() {
  return std::filesystem::temp_directory_path() / ("sim4cv_runlog_" + std::to_string(::getpid()));
}
class ScratchDirCleanup : public ::testing::Environment {
  void TearDown() override { std::filesystem::remove_all(ScratchDir()); }
};
inline ::testing::Environment* const kScratchDirCleanup = ::testing::AddGlobalTestEnvironment(new ScratchDirCleanup);

// A fresh path `name` in a directory of the current test's own.
inline std::string TempPath(const std::string& name) {
  const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
  const auto dir = ScratchDir() / (std::string(test->test_suite_name()) + "." + test->name());
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::filesystem::remove(path);
  return path;
}

inline std::vector<uint8_t> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void WriteBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// Writes `count` TestRecords with frame ids 1..count; returns the byte offset
// at which each record starts, then the file size.
inline std::vector<uint64_t> WriteTestLog(const std::string& path, int count) {
  RunLogWriter writer(path, TestHeader());
  std::vector<uint64_t> offsets{writer.bytes_written()};
  for (int i = 1; i <= count; ++i) {
    writer.Append(TestRecord(static_cast<uint64_t>(i)));
    offsets.push_back(writer.bytes_written());
  }
  return offsets;
}

// Every record the reader returns before it stops.
inline std::vector<FrameLogRecord> ReadAll(RunLogReader& reader) {
  std::vector<FrameLogRecord> records;
  FrameLogRecord record;
  while (reader.Next(&record)) records.push_back(record);
  return records;
}

}  // namespace sim4cv::runlog::testing
