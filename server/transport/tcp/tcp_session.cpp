#include "server/transport/tcp/tcp_session.h"

#include "protocol/framing.h"
#include "server/common/log.h"

namespace sim4cv::transport {

namespace asio = boost::asio;
using Outcome = session::ClientProtocol::Outcome;

TcpSession::TcpSession(asio::ip::tcp::socket socket, session::ClientId client, const session::ServerContext& context,
                       uint32_t send_buffer_bytes, OnClosed on_closed)
    : socket_(std::move(socket)), client_(client), context_(context), on_closed_(std::move(on_closed)) {
  frame_buffers_.reserve(8);
  boost::system::error_code ignored;
  socket_.set_option(asio::ip::tcp::no_delay(true), ignored);  // frames must leave at once
  if (send_buffer_bytes > 0) socket_.set_option(asio::socket_base::send_buffer_size(static_cast<int>(send_buffer_bytes)), ignored);
}

void TcpSession::Start() {
  protocol_ = std::make_unique<session::ClientProtocol>(client_, context_, shared_from_this(), mailbox_);
  ReadPrefix();
}

void TcpSession::Reject(proto::ErrorCode code, const std::string& message) {
  session::ClientProtocol::Refuse(code, message, true, reply_);
  Reply(Outcome::kReplyAndClose);
}

void TcpSession::ReadPrefix() {
  asio::async_read(socket_, asio::buffer(prefix_), [self = shared_from_this()](boost::system::error_code error, std::size_t) {
    if (error) {
      if (error != asio::error::eof && error != asio::error::operation_aborted) {
        LOG_INFO("client " << self->client_ << " read failed: " << error.message());
      }
      self->Close();
      return;
    }
    if (self->close_after_writes_) return;  // a fatal Error is on its way out: read no more
    const uint32_t size = wire::DecodeLengthPrefix(self->prefix_);
    if (size > self->context_.max_message_bytes) {
      self->Reply(session::ClientProtocol::Refuse(
          proto::ERROR_CODE_MESSAGE_TOO_LARGE,
          "length prefix announces " + std::to_string(size) + " bytes; the limit is " +
              std::to_string(self->context_.max_message_bytes) + " (daemon flag --max-message-bytes)",
          true, self->reply_));
      return;
    }
    self->ReadBody(size);
  });
}

void TcpSession::ReadBody(uint32_t size) {
  body_.resize(size);
  asio::async_read(socket_, asio::buffer(body_), [self = shared_from_this()](boost::system::error_code error, std::size_t) {
    if (error) {
      // A client that vanishes mid-message: nothing to answer, just forget it.
      LOG_INFO("client " << self->client_ << " disconnected in the middle of a message: " << error.message());
      self->Close();
      return;
    }
    if (self->close_after_writes_) return;  // a fatal Error is on its way out: answer no more
    self->HandleRequest();
  });
}

void TcpSession::HandleRequest() {
  if (!request_.ParseFromString(body_)) {
    Reply(session::ClientProtocol::Refuse(proto::ERROR_CODE_MALFORMED_MESSAGE,
                                          "the " + std::to_string(body_.size()) +
                                              " bytes after the length prefix are not a valid Envelope",
                                          true, reply_));
    return;
  }
  Reply(protocol_->Handle(request_, reply_));
}

void TcpSession::Reply(Outcome outcome) {
  if (outcome != Outcome::kNoReply) QueueEnvelope(reply_);
  if (outcome == Outcome::kReplyAndClose) {
    CloseAfterWrites(reply_);
    PumpWrites();
    return;
  }
  PumpWrites();
  ReadPrefix();
}

// After a fatal Error, from ClientProtocol or the sim thread: stop reading,
// send nothing more, close once the Error is out.
void TcpSession::CloseAfterWrites(const proto::Envelope& error) {
  LOG_INFO("client " << client_ << " refused: " << error.error().message());
  close_after_writes_ = true;
  closing_ = true;
}

void TcpSession::QueueEnvelope(const proto::Envelope& envelope) {
  std::string bytes(wire::kLengthPrefixBytes, '\0');
  envelope.AppendToString(&bytes);
  wire::EncodeLengthPrefix(static_cast<uint32_t>(bytes.size() - wire::kLengthPrefixBytes),
                           reinterpret_cast<uint8_t*>(bytes.data()));
  replies_.push_back(std::move(bytes));
}

void TcpSession::OfferFrame(const session::FrameRef& frame) {
  if (closing_) return;
  mailbox_.Offer(frame);
  WakeWriter();
}

void TcpSession::OfferReply(proto::Envelope reply) {
  if (closing_) return;  // nobody left to answer
  offered_replies_.Offer(std::move(reply));
  WakeWriter();
}

// Sim thread. One pending wake-up is enough however many offers arrive before it runs.
void TcpSession::WakeWriter() {
  if (!pump_posted_.exchange(true)) {
    asio::post(socket_.get_executor(), [self = shared_from_this()] {
      self->pump_posted_ = false;
      self->PumpWrites();
    });
  }
}

// Queues the sim thread's replies behind ClientProtocol's; nothing after a fatal Error.
void TcpSession::TakeOfferedReplies() {
  offered_replies_.TakeAll(offered_);
  for (const proto::Envelope& reply : offered_) {
    if (close_after_writes_) return;
    QueueEnvelope(reply);
    if (session::ClientProtocol::EndsConnection(reply)) CloseAfterWrites(reply);
  }
}

void TcpSession::PumpWrites() {
  if (writing_ || closed_) return;
  TakeOfferedReplies();
  if (!replies_.empty()) return WriteReply();
  if (close_after_writes_) return Close();
  if (!next_frame_) next_frame_ = mailbox_.Take();
  if (!next_frame_) return;
  // A reply offered before this frame may have arrived since the look above; it goes first.
  if (offered_replies_.pending()) return PumpWrites();
  WriteFrame(std::move(next_frame_));
}

void TcpSession::WriteReply() {
  reply_in_flight_ = std::move(replies_.front());
  replies_.pop_front();
  writing_ = true;
  asio::async_write(socket_, asio::buffer(reply_in_flight_),
                    [self = shared_from_this()](boost::system::error_code error, std::size_t) { self->OnWritten(error); });
}

void TcpSession::WriteFrame(session::FrameRef frame) {
  // A frame of the camera this client subscribed to before a re-subscribe is stale.
  if (!protocol_->subscribed() || frame->camera_index != protocol_->camera_index()) return PumpWrites();
  encoder_.Encode(*frame, frame->camera_name, protocol_->subscription(), protocol_->with_state(), mailbox_.dropped(),
                  true);
  frame_buffers_.clear();
  for (const Segment& segment : encoder_.segments()) frame_buffers_.emplace_back(segment.data, segment.size);
  frame_in_flight_ = std::move(frame);
  writing_ = true;
  asio::async_write(socket_, frame_buffers_, [self = shared_from_this()](boost::system::error_code error, std::size_t) {
    self->frame_in_flight_.reset();
    self->protocol_->OnFrameSent();
    self->OnWritten(error);
  });
}

void TcpSession::OnWritten(const boost::system::error_code& error) {
  writing_ = false;
  if (error) {
    LOG_INFO("client " << client_ << " write failed (" << error.message() << "); closing its connection");
    Close();
    return;
  }
  PumpWrites();
}

void TcpSession::Close() {
  if (closed_) return;
  closed_ = true;
  closing_ = true;
  boost::system::error_code ignored;
  socket_.shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
  socket_.close(ignored);
  if (protocol_) protocol_->Disconnect();
  next_frame_.reset();
  mailbox_.Reset(proto::DELIVERY_NEWEST);  // release frames back to the pool now
  if (on_closed_) on_closed_(client_);
}

}  // namespace sim4cv::transport
