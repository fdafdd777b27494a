// One TCP connection: reads length-prefixed Envelopes, hands them to its
// session::ClientSession (which decides what they mean and holds the frames
// and the sim thread's replies for it), writes replies and frames. Runs on
// the transport's Asio thread; the sim thread only offers to the session,
// which wakes this one.
//
// What one client can make it hold is bounded (docs/protocol.md, section 11):
// a message's bytes only as they arrive (MessageReader), replies waiting to
// be sent by back-pressure (nothing more is read from a client while they
// exceed limits::kReplyBacklogBytes), the sim thread's replies by
// OfferedReplies' bound, and time by ConnectionDeadlines (handshake, message
// and idle timeouts, then limits::kCloseLingerMs for a fatal Error to leave).
#pragma once

#include <atomic>
#include <chrono>
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
#include <boost/asio.hpp>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "server/session/client_session.h"
#include "server/transport/frame_encoding.h"
#include "server/transport/tcp/connection_deadlines.h"
#include "server/transport/tcp/message_reader.h"
#include "server/transport/tcp/tcp_transport.h"

namespace sim4cv::transport {

class TcpSession : public std::enable_shared_from_this<TcpSession> {
 public:
  using OnClosed = std::function<void(session::ClientId)>;

  TcpSession(boost::asio::ip::tcp::socket socket, session::ClientId client, const session::ServerContext& context,
             const TcpOptions& options, OnClosed on_closed);

  // Starts reading. Must be called once, on the Asio thread, after
  // construction through make_shared.
  void Start();
  // Sends a fatal Error and closes without reading anything (e.g. too many clients).
  void Reject(proto::ErrorCode code, const std::string& message);
  // Closes the socket at once and tells the sim thread the client is gone.
  void Close();

 private:
  using Clock = std::chrono::steady_clock;

  void ContinueReading();
  void ReadSome();
  void OnRead(const boost::system::error_code& error, std::size_t count);
  void HandleRequest();
  void Reply(session::ClientProtocol::Outcome outcome);
  void CloseAfterWrites(const proto::Envelope& error);
  // Appends the framed envelope to the replies; returns its size in bytes.
  std::size_t QueueEnvelope(const proto::Envelope& envelope);
  // Bytes of replies waiting to be sent: queued here, in flight, and offered by the sim thread.
  std::size_t Backlog() const { return queued_bytes_ + (session_ ? session_->reply_bytes() : 0); }
  void ArmTimer();
  void OnTimer();
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
  std::shared_ptr<session::ClientSession> session_;  // null for a client refused before Start

  // Reading (reused buffers: nothing allocated per message once warm; those
  // a large message grew are given back after it).
  MessageReader reader_;
  proto::Envelope request_;
  proto::Envelope reply_;
  bool reading_ = false;      // a read is in flight
  bool read_paused_ = false;  // back-pressure: the backlog is over its bound

  // Timeouts: one timer, set for the earliest deadline (lazily: a deadline
  // that moves later is found when the timer fires).
  ConnectionDeadlines deadlines_;
  boost::asio::steady_timer timer_;
  Clock::time_point timer_at_ = Clock::time_point::max();
  Clock::time_point close_deadline_ = Clock::time_point::max();  // after a fatal Error

  // Writing: replies go before frames; one write in flight at a time.
  std::deque<std::string> replies_;
  std::string reply_in_flight_;
  std::size_t queued_bytes_ = 0;  // replies_ and reply_in_flight_
  std::vector<proto::Envelope> offered_;  // reused: the sim thread's replies taken from the session
  session::FrameRef frame_in_flight_;
  FrameEncoder encoder_;
  std::vector<boost::asio::const_buffer> frame_buffers_;
  bool writing_ = false;
  bool close_after_writes_ = false;
  bool closed_ = false;
  std::atomic<bool> pump_posted_{false};
};

}  // namespace sim4cv::transport
