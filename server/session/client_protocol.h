// The per-connection protocol rules, the same for every transport: the
// handshake, validation of every request against the immutable scene, and
// turning accepted requests into Commands for the sim thread. Transports only
// move bytes; they ask this class what to answer.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "server/session/client_link.h"
#include "server/session/frame_mailbox.h"
#include "server/session/server_context.h"

namespace sim4cv::session {

class ClientProtocol {
 public:
  enum class Outcome {
    kNoReply,        // nothing to send
    kReply,          // send `reply`
    kReplyAndClose,  // send `reply` (a fatal Error), then close the connection
  };

  // `mailbox`: where the transport takes this client's frames from; null for
  // a transport whose frames reach the client another way (the shm ring),
  // whose subscriptions then never hold lockstep back on a full mailbox.
  ClientProtocol(ClientId client, const ServerContext& context, std::shared_ptr<ClientLink> link,
                 FrameMailbox* mailbox);

  // Handles one decoded envelope from the client; fills `reply` when the
  // outcome says so.
  Outcome Handle(const proto::Envelope& request, proto::Envelope& reply);

  // A transport-level refusal (bytes that never became an Envelope), phrased
  // the same way as every other Error.
  static Outcome Refuse(proto::ErrorCode code, const std::string& message, bool fatal, proto::Envelope& reply);

  // Whether sending `reply` ends the connection (a fatal Error), whoever
  // produced it: this class or the sim thread (ClientLink::OfferReply).
  static bool EndsConnection(const proto::Envelope& reply) { return reply.has_error() && reply.error().fatal(); }

  // The Welcome `client` gets: the daemon's fixed settings and the world as
  // the sim thread last published it.
  static void FillWelcome(const ServerContext& context, ClientId client, proto::Welcome& welcome);

  // The transport has established who the client is (the shm socket's peer
  // credentials, the studio's cookie): Hello needs no token.
  void MarkAuthenticated() { authenticated_ = true; }

  // The transport delivered one frame; a lockstep client may Step again.
  void OnFrameSent() { OnFramesSent(1); }
  // `count` frames reached the client at once (the shm ring counts them).
  void OnFramesSent(uint64_t count);

  // On-request delivery (DELIVERY_ON_REQUEST): whether the client asked for
  // a frame it has not been sent yet; the transport's session marks it
  // answered when it takes a frame to send.
  bool frame_requested() const { return frame_requested_; }
  bool on_request() const { return subscribed_ && subscription_.delivery() == proto::DELIVERY_ON_REQUEST; }
  void OnRequestAnswered() { frame_requested_ = false; }

  // The connection is gone: tell the sim thread (once).
  void Disconnect();

  ClientId client() const { return client_; }
  bool handshaken() const { return handshaken_; }
  const std::string& client_name() const { return client_name_; }
  bool subscribed() const { return subscribed_; }
  bool with_state() const { return with_state_; }
  uint32_t camera_index() const { return camera_index_; }
  // Subscribed channels in subscription order.
  const proto::Subscribed& subscription() const { return subscription_; }

 private:
  Outcome HandleHello(const proto::Hello& hello, proto::Envelope& reply);
  // Empty if `hello` may proceed; else why not (its token is missing or wrong).
  std::string RefuseToken(const proto::Hello& hello) const;
  Outcome HandleSubscribe(const proto::Subscribe& subscribe, proto::Envelope& reply);
  Outcome HandleStep(proto::Envelope& reply);
  Outcome HandleNextFrame(proto::Envelope& reply);
  Outcome HandleControls(const proto::Controls& controls, proto::Envelope& reply);
  Outcome HandleTrackerOutput(const proto::TrackerOutput& output, proto::Envelope& reply);
  // The command queue is full (CommandQueue::TryPost): `what` was dropped.
  Outcome RefuseBusy(const char* what, proto::Envelope& reply);
  Outcome HandleGetState(proto::Envelope& reply);
  Outcome HandleGetStats(proto::Envelope& reply);
  Outcome HandleConfigure(const proto::Configure& request, proto::Envelope& reply);

  ClientId client_;
  const ServerContext& context_;
  // Weak: the link (a transport session) owns this protocol object, and a
  // strong pointer back would keep every closed session alive.
  std::weak_ptr<ClientLink> link_;
  FrameMailbox* mailbox_;
  std::string client_name_;
  bool handshaken_ = false;
  bool authenticated_ = false;  // MarkAuthenticated: no token needed
  bool subscribed_ = false;
  bool with_state_ = false;
  uint32_t camera_index_ = 0;
  bool disconnected_ = false;
  proto::Subscribed subscription_;
  uint64_t outstanding_steps_ = 0;
  bool frame_requested_ = false;
  // Configures posted and not yet answered: counted up here, down by each
  // request's ConfigureReplyLink when the sim thread answers (its thread).
  std::shared_ptr<std::atomic<uint32_t>> outstanding_configures_ = std::make_shared<std::atomic<uint32_t>>(0);
};

}  // namespace sim4cv::session
