// One client's session, whatever transport carries its bytes: its
// ClientProtocol, its frame mailbox, the sim thread's replies to it, and the
// rules that tie them together: a reply offered before a frame reaches the
// client before that frame; nothing offered after the session ends (or once
// a fatal Error is on its way) is kept; a lockstep client may Step again once
// a frame is sent (or lost). It is the ClientLink the sim thread sees. A
// transport owns one per connection and only moves bytes: it hands requests
// to Handle, sends the replies and frames it takes, and is woken (`wake`)
// when the sim thread offers something. docs/architecture.md, "How to add a
// transport".
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <vector>

#include "server/session/client_link.h"
#include "server/session/client_protocol.h"
#include "server/session/frame_mailbox.h"
#include "server/session/offered_replies.h"

namespace sim4cv::session {

class ClientSession : public ClientLink, public std::enable_shared_from_this<ClientSession> {
 public:
  // `wake` runs on the sim thread after each offer and must not block (post
  // to the transport's thread, write an eventfd, ...).
  static std::shared_ptr<ClientSession> Create(ClientId client, const ServerContext& context,
                                               std::function<void()> wake);

  // Transport thread.
  ClientProtocol& protocol() { return *protocol_; }
  const ClientProtocol& protocol() const { return *protocol_; }
  ClientProtocol::Outcome Handle(const proto::Envelope& request, proto::Envelope& reply) {
    return protocol_->Handle(request, reply);
  }
  // Whether the sim thread has replies waiting, and their bytes (back-pressure).
  bool replies_pending() const { return offered_.pending(); }
  std::size_t reply_bytes() const { return offered_.bytes(); }
  // The sim thread's replies, oldest first, into `out` (cleared first).
  void TakeReplies(std::vector<proto::Envelope>& out) { offered_.TakeAll(out); }
  // The next frame to send, or null: none waits, or a reply offered before
  // it must go first (take the replies, then ask again: the frame waits
  // here). Frames of a subscription since replaced are skipped.
  FrameRef NextFrame();
  // Frames this subscription missed so far (newest-frame delivery).
  uint64_t dropped() const { return mailbox_.dropped(); }
  // A frame NextFrame gave was sent, or lost: a lockstep client may Step again.
  void FrameDone() { protocol_->OnFrameSent(); }
  // From now on the sim thread's offers are dropped (a fatal Error is on its
  // way, or the client is leaving).
  void StopOffers() { stopped_ = true; }
  // The client is gone: tells the sim thread (unless `disconnect` is false:
  // a client refused before its Hello never reached it), releases its frames
  // and its ClientProtocol. Idempotent; only the offers may come after it.
  void Close(bool disconnect);

  // Sim thread (ClientLink).
  void OfferFrame(const FrameRef& frame) override;
  void OfferReply(proto::Envelope reply) override;

 private:
  ClientSession(std::function<void()> wake) : wake_(std::move(wake)) {}

  std::function<void()> wake_;
  std::unique_ptr<ClientProtocol> protocol_;
  FrameMailbox mailbox_;
  OfferedReplies offered_;
  FrameRef next_;  // taken from the mailbox, waiting for earlier replies to go first
  std::atomic<bool> stopped_{false};
  bool closed_ = false;
};

}  // namespace sim4cv::session
