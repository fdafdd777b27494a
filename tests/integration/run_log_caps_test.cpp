// A run log nobody stops cannot fill the disk: the daemon closes it, whole,
// at --log-max-bytes or --log-max-seconds, tells the client that started it
// why, and allows LoadMap again. A StartLog whose header cannot be written
// leaves no file behind.
#include <sys/resource.h>

#include <filesystem>

#include "tests/integration/run_log_fixture.h"
#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

class RunLogCapsTest : public DaemonTest {
 protected:
  struct LogEnd {
    proto::ErrorCode code = proto::ERROR_CODE_UNSPECIFIED;
    std::string message;  // empty: the log did not end
  };

  // Starts the run log `name` for a lockstep client and steps until the
  // daemon says the log ended.
  LogEnd LogUntilItEnds(Client& client, const std::string& name) {
    client.Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
    proto::Configure start;
    start.mutable_start_log()->set_name(name);
    client.Configure(start);
    for (int i = 0; i < 600; ++i) {
      try {
        client.StepAndReceive();
      } catch (const ServerError& error) {
        EXPECT_FALSE(error.fatal()) << error.what();
        return {error.code(), error.what()};
      }
    }
    ADD_FAILURE() << "the log " << name << " did not end within 600 frames";
    return {};
  }

  // After the log ended: it no longer counts as written, and it is whole.
  LogContents ExpectClosedAndWhole(Client& client, const std::string& path) {
    EXPECT_EQ(client.GetWorld().log_file(), "");
    EXPECT_EQ(client.LoadMapByName("tracking/easy_desert").scene_name(), "tracking_easy_desert");
    LogContents log = ReadLog(path);
    EXPECT_EQ(log.ignored_bytes, 0u) << "the log ends with a whole record";
    return log;
  }
};

TEST_F(RunLogCapsTest, ALogIsClosedWholeAtItsSizeCap) {
  ScratchDir logs;
  StartDaemon({"--logs-dir", logs / "", "--log-max-bytes", "50000"});
  auto client = Connect("logger");
  const LogEnd end = LogUntilItEnds(*client, "sized");
  EXPECT_EQ(end.code, proto::ERROR_CODE_INVALID_STATE);
  EXPECT_NE(end.message.find("sized.s4log was closed after frame"), std::string::npos) << end.message;
  EXPECT_NE(end.message.find("(daemon flag --log-max-bytes 50000)"), std::string::npos) << end.message;
  const LogContents log = ExpectClosedAndWhole(*client, logs / "sized.s4log");
  const auto bytes = std::filesystem::file_size(logs / "sized.s4log");
  EXPECT_GE(bytes, 50000u);
  EXPECT_LT(bytes - 50000u, bytes / log.records.size()) << "closed within one record of the cap";
}

TEST_F(RunLogCapsTest, ALogIsClosedWholeAtItsDurationCap) {
  ScratchDir logs;
  StartDaemon({"--logs-dir", logs / "", "--log-max-seconds", "1", "--frame-hz", "30"});
  auto client = Connect("logger");
  const LogEnd end = LogUntilItEnds(*client, "timed");
  EXPECT_EQ(end.code, proto::ERROR_CODE_INVALID_STATE);
  EXPECT_NE(end.message.find("simulated seconds (daemon flag --log-max-seconds 1)"), std::string::npos)
      << end.message;
  EXPECT_EQ(ExpectClosedAndWhole(*client, logs / "timed.s4log").records.size(), 30u) << "one second at 30 Hz";
}

TEST_F(RunLogCapsTest, AStartLogThatCannotWriteItsHeaderLeavesNoFile) {
  ScratchDir logs;
  StartDaemon({"--logs-dir", logs / ""});
  auto client = Connect("logger");
  rlimit limit{16, 16};  // smaller than any header: its write fails as on a full disk
  ASSERT_EQ(::prlimit(daemon_->pid(), RLIMIT_FSIZE, &limit, nullptr), 0);
  proto::Configure start;
  start.mutable_start_log()->set_name("runs/empty");
  try {
    client->Configure(start);
    ADD_FAILURE() << "StartLog succeeded with a 16-byte file size limit";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_IO);
    EXPECT_NE(std::string(error.what()).find("StartLog: "), std::string::npos) << error.what();
  }
  EXPECT_FALSE(std::filesystem::exists(logs / "runs/empty.s4log")) << "an empty or headless log was left behind";
  EXPECT_EQ(client->GetWorld().log_file(), "");
}

}  // namespace
}  // namespace sim4cv::testing
