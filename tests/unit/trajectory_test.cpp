// Unit tests of trajectory recording, the binary file format and exact replay
// (server/sim/vehicles/trajectory.*), with real Bullet at 240 Hz.
#include "server/sim/vehicles/trajectory.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "server/sim/vehicles/car_driver.h"
#include "tests/support/no_warnings.h"
#include "tests/unit/vehicle_test_world.h"

namespace sim4cv::vehicles {
namespace {

using testing::kDt;
using testing::Steps;
using testing::TestWorld;

// 10 s of the car driven round a 30 m circle at 6 m/s: sample 0 plus 2400.
Trajectory RecordTenSeconds() {
  TestWorld world;
  const CarParams params;
  Car car(world.world, params, {30, 0}, std::numbers::pi / 2);
  std::vector<Eigen::Vector2d> circle;
  for (int i = 0; i < 360; ++i) {
    const double a = i * std::numbers::pi / 180;
    circle.emplace_back(30 * std::cos(a), 30 * std::sin(a));
  }
  CarDriver driver(params, Polyline(circle, true), 6.0);
  TrajectoryRecorder recorder(kDt);
  recorder.Record(car);
  for (int i = 0; i < Steps(10.0); ++i) {
    car.SetControls(driver.Update(car.State(), kDt));
    car.Update(kDt);
    world.Step();
    recorder.Record(car);
  }
  return recorder.trajectory();
}

// Bit-identical: every double compares equal (no tolerance anywhere).
void ExpectIdentical(const TrajectorySample& a, const TrajectorySample& b) {
  EXPECT_EQ(a.step, b.step);
  EXPECT_TRUE(a.state.position == b.state.position) << "step " << a.step;
  EXPECT_TRUE(a.state.orientation.coeffs() == b.state.orientation.coeffs()) << "step " << a.step;
  EXPECT_TRUE(a.state.linear_velocity == b.state.linear_velocity) << "step " << a.step;
  EXPECT_TRUE(a.state.angular_velocity == b.state.angular_velocity) << "step " << a.step;
  EXPECT_EQ(a.controls.steering, b.controls.steering);
  EXPECT_EQ(a.controls.throttle, b.controls.throttle);
  EXPECT_EQ(a.controls.brake, b.controls.brake);
  EXPECT_EQ(a.controls.reverse, b.controls.reverse);
}

TEST(TrajectoryTest, RecordSaveLoadReplayGivesIdenticalPosesEveryStep) {
  const Trajectory recorded = RecordTenSeconds();
  ASSERT_EQ(recorded.samples.size(), static_cast<std::size_t>(Steps(10.0)) + 1);
  const double driven = (recorded.samples.back().state.position - recorded.samples.front().state.position).norm();
  EXPECT_GT(driven, 20.0) << "the car actually moved";

  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("sim4cv_trajectory_test_" + std::to_string(::getpid()) + ".traj");
  SaveTrajectory(recorded, path.string());
  const Trajectory loaded = LoadTrajectory(path.string());
  std::filesystem::remove(path);
  ASSERT_EQ(loaded.samples.size(), recorded.samples.size());
  EXPECT_EQ(loaded.dt, recorded.dt);

  TestWorld world;
  TrajectoryPlayer player(world.world, loaded, CarParams{}.chassis_half_extents);
  ExpectIdentical(player.current(), recorded.samples[0]);
  double worst_rotation = 0;
  for (std::size_t k = 1; k < recorded.samples.size(); ++k) {
    ASSERT_TRUE(player.Advance());
    world.Step();
    ASSERT_EQ(player.index(), k);
    ExpectIdentical(player.current(), recorded.samples[k]);
    // The kinematic body is where the recording says, to Bullet's float
    // precision: its origin is the recorded position rounded to float, its
    // rotation within float rounding of the quaternion -> matrix conversion.
    const btTransform& t = player.body().getWorldTransform();
    const Eigen::Vector3d& p = recorded.samples[k].state.position;
    EXPECT_EQ(t.getOrigin().x(), static_cast<float>(p.x()));
    EXPECT_EQ(t.getOrigin().y(), static_cast<float>(p.y()));
    EXPECT_EQ(t.getOrigin().z(), static_cast<float>(p.z()));
    worst_rotation =
        std::max(worst_rotation, FromBullet(t.getRotation()).angularDistance(recorded.samples[k].state.orientation));
  }
  EXPECT_LT(worst_rotation, 1e-6);
  EXPECT_TRUE(player.finished());
  EXPECT_FALSE(player.Advance()) << "stays on the last sample";
  ExpectIdentical(player.current(), recorded.samples.back());
}

TEST(TrajectoryTest, FileLayoutIsTheDocumentedOne) {
  Trajectory t;
  t.dt = kDt;
  TrajectorySample s;
  s.step = 7;
  s.state.position = {1.5, -2.0, 0.25};
  s.controls = {0.5, 0.25, 0.0, true};
  t.samples = {s, s};
  std::ostringstream out;
  WriteTrajectory(t, out);
  const std::string bytes = out.str();
  // 32-byte header + 144 bytes per sample.
  ASSERT_EQ(bytes.size(), 32u + 2u * 144u);
  EXPECT_EQ(std::memcmp(bytes.data(), "S4CVTRJ\0", 8), 0);
  uint32_t version = 0, record_size = 0;
  double dt = 0;
  uint64_t count = 0, step = 0;
  std::memcpy(&version, bytes.data() + 8, 4);
  std::memcpy(&record_size, bytes.data() + 12, 4);
  std::memcpy(&dt, bytes.data() + 16, 8);
  std::memcpy(&count, bytes.data() + 24, 8);
  std::memcpy(&step, bytes.data() + 32, 8);
  EXPECT_EQ(version, 1u);
  EXPECT_EQ(record_size, 144u);
  EXPECT_EQ(dt, kDt);
  EXPECT_EQ(count, 2u);
  EXPECT_EQ(step, 7u);
  double x = 0, steering = 0;
  uint32_t flags = 0;
  std::memcpy(&x, bytes.data() + 32 + 8, 8);
  std::memcpy(&steering, bytes.data() + 32 + 112, 8);
  std::memcpy(&flags, bytes.data() + 32 + 136, 4);
  EXPECT_EQ(x, 1.5);
  EXPECT_EQ(steering, 0.5);
  EXPECT_EQ(flags, 1u) << "bit 0: reverse";
}

TEST(TrajectoryTest, CorruptFilesAreRejectedWithAReason) {
  Trajectory t;
  t.dt = kDt;
  t.samples.resize(3);
  std::ostringstream out;
  WriteTrajectory(t, out);
  const std::string good = out.str();
  auto read = [](std::string bytes) {
    std::istringstream in(bytes);
    return ReadTrajectory(in);
  };
  EXPECT_EQ(read(good).samples.size(), 3u);

  auto expect_error = [&](std::string bytes, const std::string& reason) {
    try {
      read(std::move(bytes));
      ADD_FAILURE() << "accepted a file that should fail with: " << reason;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  };
  std::string bad_magic = good;
  bad_magic[0] = 'X';
  expect_error(bad_magic, "bad magic");
  std::string bad_version = good;
  bad_version[8] = 2;
  expect_error(bad_version, "version 2 is not supported");
  expect_error(good.substr(0, good.size() - 1), "expected 432");
  expect_error(good + "x", "expected 432");
  expect_error(good.substr(0, 20), "truncated");
  EXPECT_THROW(LoadTrajectory("/nonexistent/sim4cv.traj"), std::invalid_argument);
}

TEST(TrajectoryTest, PlayerRefusesAnEmptyTrajectory) {
  TestWorld world;
  EXPECT_THROW(TrajectoryPlayer(world.world, Trajectory{}, {1, 1, 1}), std::invalid_argument);
}

}  // namespace
}  // namespace sim4cv::vehicles
