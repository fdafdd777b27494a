// A run log a client started that the disk cannot hold (here the daemon's
// file size limit, RLIMIT_FSIZE, which fails writes as a full disk does):
// the daemon closes the log, says so (its error line, WorldInfo.log_file
// empty again), tells the client that started it, keeps what was written readable, and no longer refuses
// LoadMap as if the log were still written.
#include <sys/resource.h>

#include "tests/integration/run_log_fixture.h"
#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

class RunLogFullDiskTest : public DaemonTest {};

TEST_F(RunLogFullDiskTest, AFailedWriteClosesTheLogAndLoadMapIsAllowedAgain) {
  ScratchDir logs;
  StartDaemon({"--logs-dir", logs / ""});
  auto client = Connect("logger");
  client->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  rlimit limit{16384, 16384};  // room for the header and a few records
  ASSERT_EQ(::prlimit(daemon_->pid(), RLIMIT_FSIZE, &limit, nullptr), 0);
  proto::Configure start;
  start.mutable_start_log()->set_name("full");
  EXPECT_EQ(client->Configure(start).log_file(), logs / "full.s4log");
  std::string told;  // the Error the client that started the log gets
  for (int i = 0; i < 200 && told.empty(); ++i) {
    try {
      client->StepAndReceive();
    } catch (const ServerError& error) {
      EXPECT_EQ(error.code(), proto::ERROR_CODE_IO);
      EXPECT_FALSE(error.fatal());
      told = error.what();
    }
  }
  EXPECT_NE(told.find("full.s4log: write record: File too large; the log was closed"), std::string::npos) << told;
  EXPECT_EQ(client->GetWorld().log_file(), "") << "the log still counts as written after its writes failed";
  EXPECT_NE(daemon_->stderr_text().find("run logging stopped, the simulation goes on"), std::string::npos);
  EXPECT_EQ(client->LoadMapByName("tracking/easy_desert").scene_name(), "tracking_easy_desert");
  const LogContents log = ReadLog(logs / "full.s4log");
  EXPECT_GT(log.records.size(), 0u);
  EXPECT_EQ(log.ignored_bytes, 0u) << "the log was cut back to its last whole record";
}

}  // namespace
}  // namespace sim4cv::testing
