// One TCP connection: reads length-prefixed Envelopes, asks ClientProtocol
// what they mean, writes replies and frames. Runs on the transport's Asio
// thread, except OfferFrame and OfferReply, which the sim thread calls.
#pragma once

#include <atomic>
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
#include <boost/asio.hpp>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "server/session/client_protocol.h"
#include "server/session/offered_replies.h"
#include "server/transport/frame_encoding.h"

namespace sim4cv::transport {

class TcpSession : public session::ClientLink, public std::enable_shared_from_this<TcpSession> {
 public:
  using OnClosed = std::function<void(session::ClientId)>;

  TcpSession(boost::asio::ip::tcp::socket socket, session::ClientId client, const session::ServerContext& context,
             uint32_t send_buffer_bytes, OnClosed on_closed);

  // Starts reading. Must be called once, on the Asio thread, after
  // construction through make_shared.
  void Start();
  // Sends a fatal Error and closes without reading anything (e.g. too many clients).
  void Reject(proto::ErrorCode code, const std::string& message);
  // Closes the socket at once and tells the sim thread the client is gone.
  void Close();

  void OfferFrame(const session::FrameRef& frame) override;
  // Queued for the Asio thread, which sends it like ClientProtocol's replies.
  void OfferReply(proto::Envelope reply) override;

 private:
  void ReadPrefix();
  void ReadBody(uint32_t size);
  void HandleRequest();
  void Reply(session::ClientProtocol::Outcome outcome);
  void CloseAfterWrites(const proto::Envelope& error);
  void QueueEnvelope(const proto::Envelope& envelope);
  void TakeOfferedReplies();
  void WakeWriter();
  void PumpWrites();
  void WriteReply();
  void WriteFrame(session::FrameRef frame);
  void OnWritten(const boost::system::error_code& error);

  boost::asio::ip::tcp::socket socket_;
  session::ClientId client_;
  const session::ServerContext& context_;
  OnClosed on_closed_;
  std::unique_ptr<session::ClientProtocol> protocol_;
  session::FrameMailbox mailbox_;

  // Reading (reused buffers: nothing allocated per message once warm).
  uint8_t prefix_[4] = {};
  std::string body_;
  proto::Envelope request_;
  proto::Envelope reply_;

  // Writing: replies go before frames; one write in flight at a time.
  std::deque<std::string> replies_;
  std::string reply_in_flight_;
  session::OfferedReplies offered_replies_;  // from the sim thread
  std::vector<proto::Envelope> offered_;     // reused: those taken from offered_replies_
  session::FrameRef next_frame_;             // taken from the mailbox, waiting for replies to go first
  session::FrameRef frame_in_flight_;
  FrameEncoder encoder_;
  std::vector<boost::asio::const_buffer> frame_buffers_;
  bool writing_ = false;
  bool close_after_writes_ = false;
  bool closed_ = false;
  // Closed, or a fatal Error is on its way: the sim thread's offers are dropped.
  std::atomic<bool> closing_{false};
  std::atomic<bool> pump_posted_{false};
};

}  // namespace sim4cv::transport
