// Helpers for the tests of the daemon's run logs (--log, --replay): a scratch
// folder, reading a whole log back, and comparing logged poses with the ones
// the daemon reported to a client.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <array>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "server/sim/log/run_log_reader.h"
#include "tests/integration/daemon_fixture.h"
#include "sim4cv.pb.h"

namespace sim4cv::testing {

// A fresh folder under /tmp, removed with everything in it.
class ScratchDir {
 public:
  ScratchDir() {
    char path[] = "/tmp/sim4cv-runlog-XXXXXX";
    if (!mkdtemp(path)) throw std::runtime_error("mkdtemp failed");
    path_ = path;
  }
  ~ScratchDir() { std::filesystem::remove_all(path_); }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  std::string operator/(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// Every record of a log, and the bytes of a torn tail the reader dropped.
struct LogContents {
  runlog::RunLogHeader header;
  std::vector<runlog::FrameLogRecord> records;
  uint64_t ignored_bytes = 0;
};

inline LogContents ReadLog(const std::string& path) {
  runlog::RunLogReader reader(path);
  LogContents log{reader.header(), {}, 0};
  runlog::FrameLogRecord record;
  while (reader.Next(&record)) log.records.push_back(record);
  log.ignored_bytes = reader.ignored_bytes();
  return log;
}

// Position, orientation (w x y z) and both velocities, for exact comparison:
// the log stores the same doubles the State message carries.
using Pose13 = std::array<double, 13>;

inline Pose13 PoseOf(const sim::BodyState& b) {
  const auto& p = b.position;
  const auto& q = b.orientation;
  const auto& v = b.linear_velocity;
  const auto& w = b.angular_velocity;
  return {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z(), v.x(), v.y(), v.z(), w.x(), w.y(), w.z()};
}

inline Pose13 PoseOf(const proto::EntityState& e) {
  const auto& p = e.position();
  const auto& q = e.orientation();
  const auto& v = e.linear_velocity();
  const auto& w = e.angular_velocity();
  return {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z(), v.x(), v.y(), v.z(), w.x(), w.y(), w.z()};
}

// The record holds exactly the entities of `state`, in its order, with the same poses.
inline void ExpectSamePoses(const proto::State& state, const runlog::FrameLogRecord& record) {
  ASSERT_EQ(record.entities.size(), static_cast<std::size_t>(state.entities_size())) << "frame " << record.frame_id;
  for (int i = 0; i < state.entities_size(); ++i) {
    const auto& logged = record.entities[static_cast<std::size_t>(i)];
    EXPECT_EQ(logged.id, state.entities(i).id()) << "frame " << record.frame_id;
    EXPECT_EQ(PoseOf(logged.body), PoseOf(state.entities(i))) << "frame " << record.frame_id << ", entity " << logged.id;
  }
}

}  // namespace sim4cv::testing
