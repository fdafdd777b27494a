// Lockstep runs are repeatable: two daemons with the same seed and scene give
// byte-identical frames.
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "protocol/conditions.h"
#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {
namespace {

uint64_t Fnv1a(uint64_t hash, const void* data, std::size_t size) {
  const auto* bytes = static_cast<const uint8_t*>(data);
  for (std::size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
  return hash;
}

// Hash of every frame's pixels, boxes and entity state over `frames` steps,
// with the classes of every box seen added to `classes`.
std::vector<uint64_t> RunAndHash(const std::vector<std::string>& args, int frames, const std::string& camera = "uav",
                                 std::set<int>* classes = nullptr) {
  DaemonProcess daemon(args);
  Client client;
  client.Connect("127.0.0.1", daemon.tcp_port(), "determinism");
  client.Subscribe(camera, kAllChannels, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  std::vector<uint64_t> hashes;
  for (int i = 0; i < frames; ++i) {
    const proto::Frame& frame = client.StepAndReceive();
    if (classes) {
      for (const proto::Box& box : frame.boxes()) classes->insert(box.object_class());
    }
    uint64_t hash = 14695981039346656037ull;
    for (const auto& image : frame.images()) hash = Fnv1a(hash, image.data().data(), image.data().size());
    const std::string boxes_and_state = [&] {
      proto::Frame copy;
      *copy.mutable_boxes() = frame.boxes();
      *copy.mutable_state() = frame.state();
      copy.set_sim_time(frame.sim_time());
      return copy.SerializeAsString();
    }();
    hashes.push_back(Fnv1a(hash, boxes_and_state.data(), boxes_and_state.size()));
  }
  client.Close();
  EXPECT_EQ(daemon.Stop(), 0);
  return hashes;
}

TEST(DeterminismTest, SameSeedGivesByteIdenticalFrames) {
  const std::vector<std::string> args = {"--seed", "42"};
  const auto first = RunAndHash(args, 120);
  const auto second = RunAndHash(args, 120);
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first[i], second[i]) << "frame " << i + 1 << " differs";
  // The frames really change over time (the hash is not of something constant).
  EXPECT_NE(first.front(), first.back());
}

// Every conditions preset, with sensor noise on: two runs give the same
// bytes frame for frame (30 frames each, every channel).
TEST(DeterminismTest, EveryPresetWithNoiseIsRepeatable) {
  for (const conditions::PresetInfo& preset : conditions::kPresets) {
    SCOPED_TRACE(preset.name);
    const std::vector<std::string> args = {"--seed", "3", "--conditions", std::string(preset.name),
                                           "--noise-read", "2", "--noise-shot", "1"};
    const auto first = RunAndHash(args, 30);
    const auto second = RunAndHash(args, 30);
    ASSERT_EQ(first.size(), second.size());
    for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first[i], second[i]) << "frame " << i + 1 << " differs";
  }
}

// With a city's traffic (lights cycling, traffic cars, walkers, parked
// cars) the runs are just as repeatable, and the first-person camera's boxes
// hold every class of it.
TEST(DeterminismTest, TrafficIsRepeatableAndLabelled) {
  const std::vector<std::string> args = {"--seed",          "7",  "--map",          SourcePath("scenes/driving/train/01_urban.map"),
                                         "--traffic-cars",  "20", "--traffic-parked", "40",
                                         "--traffic-pedestrians", "30"};
  std::set<int> classes;
  const auto first = RunAndHash(args, 150, "car_front", &classes);
  const auto second = RunAndHash(args, 150, "car_front");
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first[i], second[i]) << "frame " << i + 1 << " differs";
  for (const int wanted : {proto::OBJECT_CLASS_CAR, proto::OBJECT_CLASS_PEDESTRIAN, proto::OBJECT_CLASS_TRAFFIC_LIGHT}) {
    EXPECT_TRUE(classes.count(wanted)) << proto::ObjectClass_Name(wanted) << " never in a box";
  }
}

}  // namespace
}  // namespace sim4cv::testing
