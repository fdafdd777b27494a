// sim4cv_drive (clients/cpp/examples/driving/, docs/driving.md "C++ driving
// client") against the real daemon on the default scene, with an untrained
// WaypointNet exported at test time (tests/python/driving_onnx_export.py):
// it drives a parked car it was given, in lockstep and in realtime with UDP
// controls, and refuses a camera that does not exist.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {
namespace {

namespace fs = std::filesystem;

struct Exit {
  int status = -1;
  std::string output;
};

Exit RunCommand(const std::string& command) {
  Exit result;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return result;
  char buffer[512];
  while (std::fgets(buffer, sizeof buffer, pipe)) result.output += buffer;
  const int status = pclose(pipe);
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

const proto::EntityState* Find(const proto::State& state, uint32_t id) {
  for (const auto& e : state.entities()) {
    if (e.id() == id) return &e;
  }
  return nullptr;
}

class DrivingClientTest : public DaemonTest {
 protected:
  // One export for the whole suite (torch takes seconds to start).
  static void SetUpTestSuite() {
    model_dir_ = new fs::path(fs::temp_directory_path() / ("sim4cv_drive_test_" + std::to_string(getpid())));
    export_ =
        new Exit(RunCommand("PYTHONPATH='" + SourcePath("clients/python") + "' /usr/bin/python3 '" +
                            SourcePath("tests/python/driving_onnx_export.py") + "' '" + model_dir_->string() + "'"));
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    fs::remove_all(*model_dir_, ignored);
    delete model_dir_;
    delete export_;
  }
  void SetUp() override {
    if (export_->status == 77) GTEST_SKIP() << "torch is missing, no model to drive with: " << export_->output;
    ASSERT_EQ(export_->status, 0) << export_->output;
  }

  // Spawns a parked car "ego" on the default scene's straight, ahead of the
  // scene's own car; returns its id and its state before anyone drives it.
  uint32_t SpawnEgo(Client& client, proto::EntityState& parked) {
    const uint32_t id = client.Spawn(proto::ENTITY_KIND_CAR, "ego", 0, -42, 0, 0);
    const proto::State state = client.GetState();  // Find points into it: it must outlive the pointer
    const proto::EntityState* ego = Find(state, id);
    if (ego) parked = *ego;
    return id;
  }

  std::string Drive(const std::string& frames, const std::string& extra) {
    return std::string(SIM4CV_DRIVE) + " --model '" + (*model_dir_ / "small.onnx").string() + "' --frames " + frames +
           " --car ego --camera ego_cam " + extra;
  }

  static double Moved(const proto::EntityState& before, const proto::EntityState& after) {
    return std::hypot(after.position().x() - before.position().x(), after.position().y() - before.position().y());
  }

  static fs::path* model_dir_;
  static Exit* export_;
};

fs::path* DrivingClientTest::model_dir_ = nullptr;
Exit* DrivingClientTest::export_ = nullptr;

TEST_F(DrivingClientTest, DrivesAParkedCarInLockstep) {
  StartDaemon({"--mode", "lockstep"});
  auto client = Connect("driving-test");
  proto::EntityState parked;
  const uint32_t ego = SpawnEgo(*client, parked);
  const std::string tcp = "tcp://127.0.0.1:" + std::to_string(daemon_->tcp_port());
  const Exit run = RunCommand(Drive(tcp, "--add-camera --lockstep --frames-count 60 --max-speed 6"));
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find("added camera 'ego_cam' on 'ego'"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("drove 60 frames in "), std::string::npos) << run.output;

  const proto::State state = client->GetState();
  EXPECT_EQ(state.frame_id(), 60u) << "one Step per frame";
  const proto::EntityState* after = Find(state, ego);
  ASSERT_NE(after, nullptr);
  // Parked (brake on) until it gets Controls; the controller's throttle is
  // at least 0.3 below the speed cap, so in 2 s it must have moved.
  EXPECT_GT(Moved(parked, *after), 0.5) << after->ShortDebugString() << "\n" << run.output;
}

TEST_F(DrivingClientTest, TakesUnsetSettingsFromTheModelCardAndFlagsWin) {
  const fs::path carded = *model_dir_ / "carded";
  fs::create_directories(carded);
  fs::copy_file(*model_dir_ / "small.onnx", carded / "model.onnx", fs::copy_options::overwrite_existing);
  std::ofstream(carded / "model.json") << R"({"format": "sim4cv driving model card 1", "input": {"height": 90, )"
                                          R"("width": 160, "goal": false}, "controller": {"steer_waypoint": 3, )"
                                          R"("steer_gain": 0.5, "speed_m_s": 5}})";
  StartDaemon({"--mode", "lockstep"});
  auto client = Connect("driving-test");
  proto::EntityState parked;
  SpawnEgo(*client, parked);
  const std::string tcp = "tcp://127.0.0.1:" + std::to_string(daemon_->tcp_port());
  const std::string command = std::string(SIM4CV_DRIVE) + " --model '" + (carded / "model.onnx").string() +
                              "' --frames " + tcp + " --car ego --camera ego_cam --add-camera --lockstep " +
                              "--frames-count 5 --steer-gain 0.7";
  const Exit run = RunCommand(command);
  ASSERT_EQ(run.status, 0) << run.output;
  const std::string card = (carded / "model.json").string();
  EXPECT_NE(run.output.find("steer_waypoint 3 (model card " + card + ")"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("steer_gain 0.7 (flag)"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("speed_m_s 5 (model card " + card + ")"), std::string::npos) << run.output;

  // a card of another network is refused, naming it
  std::ofstream(carded / "model.json") << R"({"format": "sim4cv driving model card 1", "input": {"height": 180, )"
                                          R"("width": 320, "goal": false}, "controller": {}})";
  const Exit refused = RunCommand(command);
  EXPECT_EQ(refused.status, 1) << refused.output;
  EXPECT_NE(refused.output.find("model card " + card + " describes a 320x180 network, but the model is a 160x90 network"),
            std::string::npos)
      << refused.output;
}

TEST_F(DrivingClientTest, DrivesInRealtimeWithUdpControlsAndTheLaneFlip) {
  StartDaemon({"--mode", "realtime", "--udp-port", "0"});
  auto client = Connect("driving-test");
  proto::EntityState parked;
  const uint32_t ego = SpawnEgo(*client, parked);
  client->AddCamera({.name = "ego_cam", .mounted_on = "ego", .pitch_down_deg = 5, .x = 2.35, .z = 0.3});
  const std::string tcp = "tcp://127.0.0.1:" + std::to_string(daemon_->tcp_port());
  const Exit run = RunCommand(Drive(tcp, "--lane left --frames-count 20"));
  ASSERT_EQ(run.status, 0) << run.output;
  const std::string udp = "controls udp://127.0.0.1:" + ListeningField(daemon_->listening_line(), "udp");
  EXPECT_NE(run.output.find(udp), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("left lane: image flipped"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("drove 20 frames in "), std::string::npos) << run.output;
  const proto::State state = client->GetState();  // Find points into it: it must outlive the pointer
  const proto::EntityState* after = Find(state, ego);
  ASSERT_NE(after, nullptr);
  EXPECT_GT(Moved(parked, *after), 0.05) << after->ShortDebugString() << "\n" << run.output;
}

TEST_F(DrivingClientTest, ACameraThatDoesNotExistIsRefusedListingTheCameras) {
  StartDaemon({"--mode", "lockstep"});
  auto client = Connect("driving-test");
  proto::EntityState parked;
  SpawnEgo(*client, parked);
  const Exit run = RunCommand(Drive("tcp://127.0.0.1:" + std::to_string(daemon_->tcp_port()), "--lockstep"));
  EXPECT_EQ(run.status, 1) << run.output;
  EXPECT_NE(run.output.find("sim4cv_drive: no camera is named 'ego_cam'; the world's cameras: uav, car_front, "
                            "car_chase (--add-camera adds a first-person one on the car)"),
            std::string::npos)
      << run.output;
}

}  // namespace
}  // namespace sim4cv::testing
