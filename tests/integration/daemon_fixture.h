// Helpers shared by the integration tests: a running daemon plus clients
// connected to it through the real C++ client library.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "protocol/channels.h"
#include "sim4cv/client.h"
#include "tests/support/daemon_process.h"

namespace sim4cv::testing {

// Where the repository's files are (e.g. scenes/), from this header's own path.
inline std::string SourcePath(const std::string& relative) {
  return (std::filesystem::path(__FILE__).parent_path().parent_path().parent_path() / relative).string();
}

// Every channel, so the transport, determinism and replay tests cover each
// pixel channel of protocol/channels.h.
inline const std::vector<proto::Channel> kAllChannels = [] {
  std::vector<proto::Channel> all = {proto::CHANNEL_BOXES};
  for (const channels::ChannelInfo& info : channels::kPixelChannels) all.push_back(info.id);
  return all;
}();

// A fresh daemon per test; its stderr is printed if the test fails, and a
// test fails if the daemon did not exit 0 on SIGTERM.
class DaemonTest : public ::testing::Test {
 protected:
  void StartDaemon(std::vector<std::string> args = {}) { daemon_ = std::make_unique<DaemonProcess>(std::move(args)); }

  std::unique_ptr<Client> Connect(const std::string& name = "test") {
    auto client = std::make_unique<Client>();
    client->Connect("127.0.0.1", daemon_->tcp_port(), name);
    return client;
  }

  void TearDown() override {
    if (!daemon_) return;
    EXPECT_TRUE(daemon_->running()) << "sim4cvd died during the test:\n" << daemon_->stderr_text();
    EXPECT_EQ(daemon_->Stop(), 0) << daemon_->stderr_text();
    if (HasFailure()) std::cerr << "---- sim4cvd stderr ----\n" << daemon_->stderr_text();
  }

  std::unique_ptr<DaemonProcess> daemon_;
};

}  // namespace sim4cv::testing
