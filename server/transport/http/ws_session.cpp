#include "server/transport/http/ws_session.h"

#include "server/common/diagnostics.h"
#include "server/common/limits.h"
#include "server/transport/http/json_envelope.h"

namespace sim4cv::transport {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using Outcome = session::ClientProtocol::Outcome;

WsSession::WsSession(beast::tcp_stream stream, uint64_t key, HttpHub& hub, WsViewOptions view)
    : StreamSession(stream.get_executor(), session::NewClientId(), hub.options.timeouts, "WebSocket"),
      ws_(std::move(stream)),
      key_(key),
      hub_(hub),
      view_(view) {
  beast::get_lowest_layer(ws_).expires_never();  // the WebSocket's own timeouts rule from here
  websocket::stream_base::timeout timeouts{};
  const uint32_t handshake_ms = hub.options.timeouts.handshake_ms;
  timeouts.handshake_timeout =
      handshake_ms == 0 ? websocket::stream_base::none() : std::chrono::milliseconds(handshake_ms);
  timeouts.idle_timeout = std::chrono::milliseconds(limits::kWebSocketIdleTimeoutMs);
  timeouts.keep_alive_pings = true;
  ws_.set_option(timeouts);
  ws_.read_message_max(0);  // no limit of Beast's: ReadSome refuses an oversized message with an Error first
  ws_.auto_fragment(false);
  boost::system::error_code ignored;
  auto& socket = beast::get_lowest_layer(ws_).socket();
  socket.set_option(asio::ip::tcp::no_delay(true), ignored);
  if (hub.options.send_buffer_bytes > 0) {
    socket.set_option(asio::socket_base::send_buffer_size(static_cast<int>(hub.options.send_buffer_bytes)), ignored);
  }
}

void WsSession::Accept(Request request, std::function<void()> then) {
  upgrade_request_ = std::move(request);  // kept until the upgrade completes
  ws_.async_accept(upgrade_request_,
                   [self = shared_from_this(), then = std::move(then)](boost::system::error_code error) {
                     if (self->closed_) return;
                     if (error) {
                       LOG_INFO("client " << self->client_ << " WebSocket upgrade failed: " << error.message());
                       return self->Close();
                     }
                     self->accepted_ = true;
                     self->upgrade_request_ = {};  // its headers are not needed any more
                     then();
                   });
}

void WsSession::Start(Request request, bool authenticated) {
  Accept(std::move(request), [this, authenticated] {
    CreateSession(*hub_.context);
    if (authenticated) session_->protocol().MarkAuthenticated();
    LOG_INFO("client " << client_ << " connected over WebSocket");
    ArmTimer();
    ContinueReading();
  });
}

void WsSession::Reject(Request request, proto::ErrorCode code, const std::string& message) {
  Accept(std::move(request), [this, code, message] {
    session::ClientProtocol::Refuse(code, message, true, reply_);
    Reply(Outcome::kReplyAndClose);
  });
}

void WsSession::ReadSome() {
  reading_ = true;
  ws_.async_read_some(
      read_buffer_, limits::kReadChunkBytes,
      [self = shared_from_this()](boost::system::error_code error, std::size_t) { self->OnRead(error); });
}

void WsSession::OnRead(const boost::system::error_code& error) {
  reading_ = false;
  if (closed_) return;
  if (error) {
    // Malformed frames end here: Beast has already sent the close frame with
    // the RFC 6455 status (1002 protocol error, 1007 bad UTF-8).
    if (error == websocket::error::closed || error == asio::error::eof || error == asio::error::not_connected ||
        error == asio::error::connection_reset) {
      LOG_INFO("client " << client_ << " closed its WebSocket");
    } else if (error != asio::error::operation_aborted) {
      LOG_INFO("client " << client_ << " WebSocket read failed: " << error.message());
    }
    return Close();
  }
  if (close_after_writes_) return;  // a fatal Error is on its way out: read no more
  const auto now = Clock::now();
  deadlines_.Active(now);
  const uint32_t max_bytes = hub_.context->max_message_bytes;
  if (read_buffer_.size() > max_bytes) {
    return Reply(session::ClientProtocol::Refuse(proto::ERROR_CODE_MESSAGE_TOO_LARGE,
                                                 "a WebSocket message grew past " + std::to_string(max_bytes) +
                                                     " bytes, the limit (daemon flag --max-message-bytes)",
                                                 true, reply_));
  }
  if (!ws_.is_message_done()) {
    if (!message_started_) {
      message_started_ = true;
      deadlines_.MessageStarted(now);
      ArmTimer();
    }
    return ReadSome();
  }
  message_started_ = false;
  deadlines_.MessageEnded();
  HandleMessage();
}

void WsSession::HandleMessage() {
  const std::size_t size = read_buffer_.size();
  Outcome outcome;
  if (ws_.got_binary()) {
    outcome = session::ClientProtocol::Refuse(proto::ERROR_CODE_UNEXPECTED_MESSAGE,
                                              "a binary message of " + std::to_string(size) +
                                                  " bytes: send each Envelope as JSON in a text message "
                                                  "(docs/protocol.md, \"WebSocket\")",
                                              false, reply_);
  } else {
    const std::string problem =
        EnvelopeFromJson({static_cast<const char*>(read_buffer_.data().data()), size}, request_);
    if (!problem.empty()) {
      // The message's bounds are intact (unlike a TCP stream's), so the
      // connection goes on: a page's bug costs one request, not the session.
      outcome = session::ClientProtocol::Refuse(
          proto::ERROR_CODE_MALFORMED_MESSAGE,
          "the text message of " + std::to_string(size) + " bytes is not a JSON Envelope: " + problem, false, reply_);
    } else {
      outcome = session_->Handle(request_, reply_);
      if (reply_.has_welcome()) deadlines_.Handshaken();
    }
  }
  read_buffer_.consume(size);
  // A large message's buffer and parsed fields would keep its memory: give them back.
  if (size > limits::kKeptBufferBytes) {
    read_buffer_.shrink_to_fit();
    request_ = proto::Envelope();
  }
  ArmTimer();  // the next deadline may be sooner now (the idle one after the handshake's)
  Reply(outcome);
}

void WsSession::Reply(Outcome outcome) {
  if (outcome != Outcome::kNoReply) QueueEnvelope(reply_);
  if (outcome == Outcome::kReplyAndClose) CloseAfterWrites(reply_);
  if (reply_.ByteSizeLong() > limits::kKeptBufferBytes) reply_ = proto::Envelope();
  PumpWrites();
  ContinueReading();
}

// After a fatal Error: read no more, send nothing after it, then the close
// handshake with the status that fits, or a hard close after kCloseLingerMs.
void WsSession::CloseAfterWrites(const proto::Envelope& error) {
  switch (error.error().code()) {
    case proto::ERROR_CODE_TOO_MANY_CLIENTS:
      close_code_ = websocket::close_code::try_again_later;
      break;
    case proto::ERROR_CODE_MESSAGE_TOO_LARGE:
      close_code_ = websocket::close_code::too_big;
      break;
    default:
      close_code_ = websocket::close_code::policy_error;
  }
  StopAfter(error);
}

void WsSession::QueueEnvelope(const proto::Envelope& envelope) {
  EnvelopeToJson(envelope, json_);
  queued_bytes_ += json_.size();
  replies_.push_back(json_);
}

void WsSession::PumpWrites() {
  if (writing_ || closing_ || closed_ || !accepted_) return;
  TakeOfferedReplies();
  if (!replies_.empty()) return WriteReply();
  if (close_after_writes_) return CloseHandshake();
  if (!session_) return;
  session::FrameRef frame = session_->NextFrame();
  if (frame) return WriteFrame(std::move(frame));
  if (session_->replies_pending()) PumpWrites();
}

void WsSession::WriteReply() {
  reply_in_flight_ = std::move(replies_.front());
  replies_.pop_front();
  writing_ = true;
  ws_.text(true);
  ws_.async_write(asio::buffer(reply_in_flight_),
                  [self = shared_from_this()](boost::system::error_code error, std::size_t) {
                    self->queued_bytes_ -= self->reply_in_flight_.size();
                    if (self->reply_in_flight_.capacity() > limits::kKeptBufferBytes) {
                      std::string().swap(self->reply_in_flight_);
                    }
                    self->OnWritten(error);
                  });
}

// The Frame's text message, then its binary one; the frame stays referenced
// (its planes are sent from where the renderer wrote them) until both are out.
void WsSession::WriteFrame(session::FrameRef frame) {
  try {
    frame_writer_.Build(*frame, *session_, view_);
  } catch (const std::exception& error) {  // libjpeg's; an exception must not end the Asio thread
    LOG_WARNING("client " << client_ << ": cannot encode frame " << frame->frame_id << " (" << error.what()
                          << "); closing its WebSocket");
    session_->FrameDone();
    return Close();
  }
  frame_in_flight_ = std::move(frame);
  writing_ = true;
  ws_.text(true);
  ws_.async_write(
      asio::buffer(frame_writer_.header()), [self = shared_from_this()](boost::system::error_code error, std::size_t) {
        auto done = [self](const boost::system::error_code& result) {
          self->frame_in_flight_.reset();
          self->session_->FrameDone();
          self->OnWritten(result);
        };
        if (error || self->closed_) return done(error);
        self->ws_.binary(true);
        self->ws_.async_write(self->frame_writer_.binary(),
                              [done](boost::system::error_code binary_error, std::size_t) { done(binary_error); });
      });
}

void WsSession::OnWritten(const boost::system::error_code& error) {
  writing_ = false;
  if (closed_) return;
  if (error) {
    LOG_INFO("client " << client_ << " WebSocket write failed (" << error.message() << "); closing it");
    return Close();
  }
  deadlines_.Active(Clock::now());
  PumpWrites();
  if (read_paused_) ContinueReading();
}

void WsSession::CloseHandshake() {
  closing_ = true;
  ws_.async_close(websocket::close_reason(close_code_, "see the Error before this"),
                  [self = shared_from_this()](boost::system::error_code) { self->Close(); });
}

void WsSession::Close() {
  if (closed_) return;
  closed_ = true;
  boost::system::error_code ignored;
  auto& socket = beast::get_lowest_layer(ws_).socket();
  socket.shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
  socket.close(ignored);
  timer_.cancel();
  if (session_) session_->Close(true);
  hub_.Forget(key_);
}

}  // namespace sim4cv::transport
