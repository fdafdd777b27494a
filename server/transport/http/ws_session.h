// One WebSocket client: a client session exactly like a TCP connection (its
// session::ClientSession decides what every request means), with Envelopes
// as JSON text messages and each Frame as a text message plus a binary one
// (WsFrameWriter). Runs on the HTTP transport's Asio thread; the sim thread
// only offers to the session, which wakes this one.
//
// Bounded as TCP is (docs/protocol.md, "WebSocket"): a message is read in
// pieces and refused past --max-message-bytes; nothing more is read while
// more than limits::kReplyBacklogBytes of replies wait; one frame is in
// flight at a time and the mailbox keeps only the newest for a viewer;
// ConnectionDeadlines times the Hello and a started message, and Beast's
// keep-alive pings close a connection silent for
// limits::kWebSocketIdleTimeoutMs (a page that stops reading).
#pragma once

// clang-format off
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
// clang-format on

#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "server/session/client_session.h"
#include "server/transport/http/http_hub.h"
#include "server/transport/http/ws_frame_writer.h"
#include "server/transport/stream_session.h"
#include "server/transport/tcp/connection_deadlines.h"

namespace sim4cv::transport {

class WsSession : public HttpPeer, public StreamSession<WsSession>, public std::enable_shared_from_this<WsSession> {
 public:
  // `key`: the connection's entry in the hub, forgotten when it closes.
  WsSession(boost::beast::tcp_stream stream, uint64_t key, HttpHub& hub, WsViewOptions view);

  // Completes the upgrade `request` asked for and serves the client. Must be
  // called once, on the Asio thread, after construction through make_shared.
  // `authenticated`: the request's cookie carried the access token.
  void Start(boost::beast::http::request<boost::beast::http::empty_body> request, bool authenticated);
  // Completes the upgrade, sends this fatal Error and closes (over the cap).
  void Reject(boost::beast::http::request<boost::beast::http::empty_body> request, proto::ErrorCode code,
              const std::string& message);
  void Close() override;
  bool half_open() const override { return !session_ || !session_->protocol().handshaken(); }

 private:
  friend class StreamSession<WsSession>;
  using Request = boost::beast::http::request<boost::beast::http::empty_body>;

  void Accept(Request request, std::function<void()> then);
  bool CanRead() const { return accepted_; }
  void ReadSome();
  void OnRead(const boost::system::error_code& error);
  void HandleMessage();
  void Reply(session::ClientProtocol::Outcome outcome);
  void CloseAfterWrites(const proto::Envelope& error);
  void QueueEnvelope(const proto::Envelope& envelope);
  void PumpWrites();
  void WriteReply();
  void WriteFrame(session::FrameRef frame);
  void OnWritten(const boost::system::error_code& error);
  void CloseHandshake();

  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
  uint64_t key_;
  HttpHub& hub_;
  WsViewOptions view_;

  // Reading: a message in pieces of limits::kReadChunkBytes into one buffer.
  Request upgrade_request_;
  boost::beast::flat_buffer read_buffer_;
  bool accepted_ = false;
  bool message_started_ = false;  // a message's first piece arrived, not its last

  std::string json_;  // reused
  WsFrameWriter frame_writer_;
  boost::beast::websocket::close_code close_code_ = boost::beast::websocket::close_code::normal;
  bool closing_ = false;  // the close handshake is under way
};

}  // namespace sim4cv::transport
