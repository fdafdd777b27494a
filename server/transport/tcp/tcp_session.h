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

// clang-format off
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
// clang-format on
#include <boost/asio.hpp>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "server/session/client_session.h"
#include "server/transport/frame_encoding.h"
#include "server/transport/stream_session.h"
#include "server/transport/tcp/connection_deadlines.h"
#include "server/transport/tcp/message_reader.h"
#include "server/transport/tcp/tcp_transport.h"

namespace sim4cv::transport {

class TcpSession : public StreamSession<TcpSession>, public std::enable_shared_from_this<TcpSession> {
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
  // Whether its Hello was accepted; a connection that has not is half-open,
  // the first to go when the slots run out.
  bool handshaken() const { return session_ && session_->protocol().handshaken(); }

 private:
  friend class StreamSession<TcpSession>;

  bool CanRead() const { return true; }
  void ReadSome();
  void OnRead(const boost::system::error_code& error, std::size_t count);
  void HandleRequest();
  void Reply(session::ClientProtocol::Outcome outcome);
  void CloseAfterWrites(const proto::Envelope& error) { StopAfter(error); }
  // Appends the framed envelope to the replies; returns its size in bytes.
  std::size_t QueueEnvelope(const proto::Envelope& envelope);
  void PumpWrites();
  void WriteReply();
  void WriteFrame(session::FrameRef frame);
  void OnWritten(const boost::system::error_code& error);

  boost::asio::ip::tcp::socket socket_;
  const session::ServerContext& context_;
  OnClosed on_closed_;

  // Reading (reused buffers: nothing allocated per message once warm; those
  // a large message grew are given back after it).
  MessageReader reader_;

  FrameEncoder encoder_;
  std::vector<boost::asio::const_buffer> frame_buffers_;
};

}  // namespace sim4cv::transport
