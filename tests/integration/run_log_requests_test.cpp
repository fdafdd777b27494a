// Run logs started and stopped by a client (StartLog, StopLog) against the
// real daemon: only under --logs-dir, one at a time, the header holding the
// world of the moment, one record per frame between the two requests,
// LoadMap and Reset refused while it is written, and nothing lost when the
// daemon stops with a log still open.
#include <filesystem>

#include "tests/integration/run_log_fixture.h"
#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

namespace fs = std::filesystem;

class RunLogRequestTest : public ConfigureTest {
 protected:
  void StartWithLogsDir() {
    StartDaemon({"--logs-dir", logs_ / ""});
    client_ = Connect("logger");
    client_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  }
  proto::Configured Start(const std::string& name, const std::string& label = "", bool overwrite = false) {
    proto::Configure request;
    request.mutable_start_log()->set_name(name);
    request.mutable_start_log()->set_label(label);
    request.mutable_start_log()->set_overwrite(overwrite);
    return client_->Configure(request);
  }
  proto::Configured Stop() {
    proto::Configure request;
    request.mutable_stop_log();
    return client_->Configure(request);
  }

  ScratchDir logs_;
  std::unique_ptr<Client> client_;
};

TEST_F(RunLogRequestTest, ALogHoldsTheFramesBetweenStartAndStop) {
  StartWithLogsDir();
  StepFrames(*client_, 10);
  const proto::Configured started = Start("studio/alice", "alice, keyboard");
  const std::string path = logs_ / "studio/alice.s4log";
  EXPECT_EQ(started.log_file(), path);
  EXPECT_EQ(started.world().log_file(), path);
  StepFrames(*client_, 25);
  ExpectRefused([&] { client_->Reset(); }, proto::ERROR_CODE_INVALID_STATE,
                {"Reset is refused while the daemon writes the run log " + path, "StopLog first"});
  ExpectRefused([&] { Start("other"); }, proto::ERROR_CODE_INVALID_STATE, {"already writes the run log", path});
  const proto::Configured stopped = Stop();
  EXPECT_EQ(stopped.log_file(), path);
  EXPECT_EQ(stopped.world().log_file(), "");
  StepFrames(*client_, 5);

  const LogContents log = ReadLog(path);
  EXPECT_EQ(log.header.label, "alice, keyboard");
  EXPECT_EQ(log.header.scene_name, "default");
  ASSERT_EQ(log.records.size(), 25u) << "one record per frame between StartLog and StopLog";
  EXPECT_EQ(log.records.front().frame_id, 11u);
  EXPECT_EQ(log.records.back().frame_id, 35u);
  EXPECT_EQ(log.ignored_bytes, 0u);

  client_->Reset();  // allowed again
  ExpectRefused([&] { Stop(); }, proto::ERROR_CODE_INVALID_STATE, {"no run log is being written"});
  ExpectRefused([&] { Start("studio/alice"); }, proto::ERROR_CODE_ALREADY_EXISTS, {"alice.s4log' exists", "overwrite"});
  Start("studio/alice", "", /*overwrite=*/true);
  StepFrames(*client_, 3);
  Stop();
  EXPECT_EQ(ReadLog(path).records.size(), 3u);
}

TEST_F(RunLogRequestTest, AMapLoadedBeforeTheLogIsItsHeader) {
  StartDaemon({"--logs-dir", logs_ / ""});
  client_ = Connect("logger");
  client_->LoadMapByName("tracking/easy_desert");
  client_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  client_->SetConditions("dusk");
  Start("desert");
  ExpectRefused([&] { client_->LoadMapByName("tracking/easy_urban"); }, proto::ERROR_CODE_INVALID_STATE,
                {"LoadMap is refused while the daemon writes the run log", "a log holds one map"});
  StepFrames(*client_, 4);
  const std::string path = logs_ / "desert.s4log";
  // The daemon stops with the log open: it is closed whole, nothing lost.
  EXPECT_EQ(daemon_->Stop(), 0) << daemon_->stderr_text();
  daemon_.reset();
  const LogContents log = ReadLog(path);
  EXPECT_EQ(log.header.scene_name, "tracking_easy_desert");
  EXPECT_NE(log.header.map_path.find("tracking/easy_desert.map"), std::string::npos) << log.header.map_path;
  EXPECT_NE(log.header.conditions.find("dusk"), std::string::npos) << log.header.conditions;
  EXPECT_EQ(log.records.size(), 4u);
}

TEST_F(RunLogRequestTest, RefusedWithoutLogsDirAndOutsideIt) {
  StartDaemon();
  client_ = Connect("logger");
  ExpectRefused([&] { Start("x"); }, proto::ERROR_CODE_INVALID_STATE, {"without --logs-dir", "--log FILE"});
  client_.reset();
  daemon_->Stop();
  daemon_.reset();

  StartWithLogsDir();
  for (const char* name : {"../x", "/tmp/x", ".hidden", "a//b", ""}) {
    ExpectRefused([&] { Start(name); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"StartLog.name"});
  }
  fs::create_directory_symlink("/tmp", logs_ / "out");
  ExpectRefused([&] { Start("out/x"); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"is a symbolic link"});
  EXPECT_FALSE(fs::exists("/tmp/x.s4log"));
}

TEST_F(RunLogRequestTest, ALogOfTheFlagIsNotStoppedByAClient) {
  const std::string path = logs_ / "flag.s4log";
  StartDaemon({"--log", path, "--logs-dir", logs_ / ""});
  client_ = Connect("logger");
  ExpectRefused([&] { Stop(); }, proto::ERROR_CODE_INVALID_STATE, {"--log " + path, "ends with the daemon"});
  ExpectRefused([&] { Start("x"); }, proto::ERROR_CODE_INVALID_STATE, {"(--log), which ends with the daemon"});
  EXPECT_EQ(client_->GetWorld().log_file(), path);
}

}  // namespace
}  // namespace sim4cv::testing
