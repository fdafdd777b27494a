#include "server/transport/tcp/tcp_session.h"

#include "protocol/framing.h"
#include "server/common/diagnostics.h"
#include "server/common/limits.h"

namespace sim4cv::transport {

namespace asio = boost::asio;
using Outcome = session::ClientProtocol::Outcome;

TcpSession::TcpSession(asio::ip::tcp::socket socket, session::ClientId client, const session::ServerContext& context,
                       const TcpOptions& options, OnClosed on_closed)
    : StreamSession(socket.get_executor(), client, options.timeouts, "connection"),
      socket_(std::move(socket)),
      context_(context),
      on_closed_(std::move(on_closed)),
      reader_(context.max_message_bytes) {
  frame_buffers_.reserve(2 * channels::kPixelChannelCount + 1);  // FrameEncoder's most segments
  boost::system::error_code ignored;
  socket_.set_option(asio::ip::tcp::no_delay(true), ignored);  // frames must leave at once
  if (options.send_buffer_bytes > 0) {
    socket_.set_option(asio::socket_base::send_buffer_size(static_cast<int>(options.send_buffer_bytes)), ignored);
  }
}

void TcpSession::Start() {
  CreateSession(context_);
  ArmTimer();
  ContinueReading();
}

void TcpSession::Reject(proto::ErrorCode code, const std::string& message) {
  session::ClientProtocol::Refuse(code, message, true, reply_);
  Reply(Outcome::kReplyAndClose);
}

void TcpSession::ReadSome() {
  reading_ = true;
  socket_.async_read_some(
      asio::buffer(reader_.next_data(), reader_.next_size()),
      [self = shared_from_this()](boost::system::error_code error, std::size_t count) { self->OnRead(error, count); });
}

void TcpSession::OnRead(const boost::system::error_code& error, std::size_t count) {
  reading_ = false;
  if (closed_) return;
  if (error) {
    if (reader_.started()) {
      // A client that vanishes mid-message: nothing to answer, just forget it.
      LOG_INFO("client " << client_ << " disconnected in the middle of a message: " << error.message());
    } else if (error != asio::error::eof && error != asio::error::operation_aborted) {
      LOG_INFO("client " << client_ << " read failed: " << error.message());
    }
    Close();
    return;
  }
  if (close_after_writes_) return;  // a fatal Error is on its way out: read no more
  const auto now = Clock::now();
  deadlines_.Active(now);
  const bool first_bytes = !reader_.started();
  switch (reader_.Advance(count)) {
    case MessageReader::Status::kNeedMore:
      if (first_bytes) {
        deadlines_.MessageStarted(now);
        ArmTimer();
      }
      return ReadSome();
    case MessageReader::Status::kTooLarge:
      return Reply(session::ClientProtocol::Refuse(
          proto::ERROR_CODE_MESSAGE_TOO_LARGE,
          "length prefix announces " + std::to_string(reader_.announced()) + " bytes; the limit is " +
              std::to_string(context_.max_message_bytes) + " (daemon flag --max-message-bytes)",
          true, reply_));
    case MessageReader::Status::kComplete:
      deadlines_.MessageEnded();
      return HandleRequest();
  }
}

void TcpSession::HandleRequest() {
  const std::string& body = reader_.body();
  Outcome outcome;
  if (!request_.ParseFromString(body)) {
    outcome = session::ClientProtocol::Refuse(
        proto::ERROR_CODE_MALFORMED_MESSAGE,
        "the " + std::to_string(body.size()) + " bytes after the length prefix are not a valid Envelope", true, reply_);
  } else {
    outcome = session_->Handle(request_, reply_);
    if (reply_.has_welcome()) deadlines_.Handshaken();
  }
  // The parsed fields of a large message would keep its memory: give it back.
  if (body.size() > limits::kKeptBufferBytes) request_ = proto::Envelope();
  reader_.Next();
  ArmTimer();  // the next deadline may be sooner now (e.g. the idle one after the handshake's)
  Reply(outcome);
}

void TcpSession::Reply(Outcome outcome) {
  std::size_t size = 0;
  if (outcome != Outcome::kNoReply) size = QueueEnvelope(reply_);
  if (outcome == Outcome::kReplyAndClose) CloseAfterWrites(reply_);
  if (size > limits::kKeptBufferBytes) reply_ = proto::Envelope();  // e.g. a Welcome with a large world
  PumpWrites();
  ContinueReading();
}

std::size_t TcpSession::QueueEnvelope(const proto::Envelope& envelope) {
  std::string bytes(wire::kLengthPrefixBytes, '\0');
  envelope.AppendToString(&bytes);
  wire::EncodeLengthPrefix(static_cast<uint32_t>(bytes.size() - wire::kLengthPrefixBytes),
                           reinterpret_cast<uint8_t*>(bytes.data()));
  const std::size_t size = bytes.size();
  queued_bytes_ += size;
  replies_.push_back(std::move(bytes));
  return size;
}

void TcpSession::PumpWrites() {
  if (writing_ || closed_) return;
  TakeOfferedReplies();
  if (!replies_.empty()) return WriteReply();
  if (close_after_writes_) return Close();
  if (!session_) return;
  session::FrameRef frame = session_->NextFrame();
  if (frame) return WriteFrame(std::move(frame));
  // None, or a reply offered before the next frame arrived meanwhile: it goes first.
  if (session_->replies_pending()) PumpWrites();
}

void TcpSession::WriteReply() {
  reply_in_flight_ = std::move(replies_.front());
  replies_.pop_front();
  writing_ = true;
  asio::async_write(socket_, asio::buffer(reply_in_flight_),
                    [self = shared_from_this()](boost::system::error_code error, std::size_t) {
                      self->queued_bytes_ -= self->reply_in_flight_.size();
                      // A large reply's buffer goes back once it is out.
                      if (self->reply_in_flight_.capacity() > limits::kKeptBufferBytes) {
                        std::string().swap(self->reply_in_flight_);
                      }
                      self->OnWritten(error);
                    });
}

void TcpSession::WriteFrame(session::FrameRef frame) {
  encoder_.Encode(*frame, *session_, true);
  frame_buffers_.clear();
  for (const Segment& segment : encoder_.segments()) frame_buffers_.emplace_back(segment.data, segment.size);
  frame_in_flight_ = std::move(frame);
  writing_ = true;
  asio::async_write(socket_, frame_buffers_, [self = shared_from_this()](boost::system::error_code error, std::size_t) {
    self->frame_in_flight_.reset();
    self->session_->FrameDone();
    self->OnWritten(error);
  });
}

void TcpSession::OnWritten(const boost::system::error_code& error) {
  writing_ = false;
  if (closed_) return;
  if (error) {
    LOG_INFO("client " << client_ << " write failed (" << error.message() << "); closing its connection");
    Close();
    return;
  }
  deadlines_.Active(Clock::now());
  PumpWrites();
  if (read_paused_) ContinueReading();  // back-pressure: the backlog may have drained below its bound
}

void TcpSession::Close() {
  if (closed_) return;
  closed_ = true;
  boost::system::error_code ignored;
  socket_.shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
  socket_.close(ignored);
  timer_.cancel();
  if (session_) session_->Close(true);
  if (on_closed_) on_closed_(client_);
}

}  // namespace sim4cv::transport
