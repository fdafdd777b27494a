#include "server/session/client_session.h"

namespace sim4cv::session {

std::shared_ptr<ClientSession> ClientSession::Create(ClientId client, const ServerContext& context,
                                                     std::function<void()> wake) {
  std::shared_ptr<ClientSession> session(new ClientSession(std::move(wake)));
  session->protocol_ = std::make_unique<ClientProtocol>(client, context, session, &session->mailbox_);
  return session;
}

FrameRef ClientSession::NextFrame() {
  // On request, a frame waits in the mailbox (replaced by newer ones) until asked for.
  if (protocol_->on_request() && !protocol_->frame_requested()) return {};
  for (;;) {
    if (!next_) next_ = mailbox_.Take();
    if (!next_) return {};
    // A reply offered before this frame may have arrived since the transport
    // last took replies: it goes first, and the frame waits.
    if (offered_.pending()) return {};
    FrameRef frame = std::move(next_);
    // A frame of the camera this client subscribed to before a re-subscribe is stale.
    if (protocol_->subscribed() && frame->camera_index == protocol_->camera_index()) {
      protocol_->OnRequestAnswered();
      return frame;
    }
  }
}

void ClientSession::Close(bool disconnect) {
  if (closed_) return;
  closed_ = true;
  stopped_ = true;
  if (disconnect) protocol_->Disconnect();
  next_.reset();
  mailbox_.Reset(proto::DELIVERY_NEWEST);  // release frames back to the pool now
}

void ClientSession::OfferFrame(const FrameRef& frame) {
  if (stopped_) return;
  mailbox_.Offer(frame);
  wake_();
}

void ClientSession::OfferReply(proto::Envelope reply) {
  if (stopped_) return;  // nobody left to answer
  offered_.Offer(std::move(reply));
  wake_();
}

}  // namespace sim4cv::session
