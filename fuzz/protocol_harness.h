// What ClientProtocol needs from a daemon, built without one (as
// tests/unit/client_protocol_test.cpp does): the shared ServerContext with a
// published world of one camera, and a client session (its link, mailbox and
// protocol object) as a transport makes one per connection.
#pragma once

#include <memory>
#include <vector>

#include "server/session/client_protocol.h"
#include "server/session/command_queue.h"
#include "server/session/counters.h"
#include "server/session/server_context.h"

namespace sim4cv::fuzz {

// The daemon side shared by every connection; built once per fuzzer process.
class ProtocolHarness {
 public:
  explicit ProtocolHarness(proto::SimMode mode = proto::SIM_MODE_LOCKSTEP);
  const session::ServerContext& context() const { return context_; }
  // What the sim thread would do with the posted Commands between two
  // inputs: take them all (dropping their links), so nothing piles up.
  void DrainCommands();

 private:
  sim::Scene scene_;
  session::WorldDirectory world_;
  session::CommandQueue commands_;
  session::StatePool state_pool_;  // outlives latest_state_'s ref
  session::LatestState latest_state_;
  session::Counters counters_;
  session::ServerContext context_;
  std::vector<session::Command> drained_;
};

// The lockstep harness of a protocol fuzzer's process, built on first use
// with the logs quieted to warnings (every input would log its refusals).
ProtocolHarness& SharedHarness();

// A link that keeps what the sim thread offers, as a transport session would
// queue it, until the next input.
class RecordingLink : public session::ClientLink {
 public:
  void OfferFrame(const session::FrameRef&) override {}
  void OfferReply(proto::Envelope reply) override { replies.push_back(std::move(reply)); }
  std::vector<proto::Envelope> replies;
};

// One client connection: a fresh protocol object, as a new TCP session has.
struct FuzzSession {
  explicit FuzzSession(const session::ServerContext& context);
  ~FuzzSession();
  session::FramePool frame_pool;  // outlives the mailbox's refs
  session::FrameMailbox mailbox;
  std::shared_ptr<RecordingLink> link = std::make_shared<RecordingLink>();
  session::ClientProtocol protocol;
};

}  // namespace sim4cv::fuzz
