#include "server/transport/tcp/tcp_session.h"

#include "protocol/framing.h"
#include "server/common/limits.h"
#include "server/common/diagnostics.h"

namespace sim4cv::transport {

namespace asio = boost::asio;
using Outcome = session::ClientProtocol::Outcome;

TcpSession::TcpSession(asio::ip::tcp::socket socket, session::ClientId client, const session::ServerContext& context,
                       const TcpOptions& options, OnClosed on_closed)
    : socket_(std::move(socket)),
      client_(client),
      context_(context),
      on_closed_(std::move(on_closed)),
      reader_(context.max_message_bytes),
      deadlines_(options.timeouts, Clock::now()),
      timer_(socket_.get_executor()) {
  frame_buffers_.reserve(2 * channels::kPixelChannelCount + 1);  // FrameEncoder's most segments
  boost::system::error_code ignored;
  socket_.set_option(asio::ip::tcp::no_delay(true), ignored);  // frames must leave at once
  if (options.send_buffer_bytes > 0) {
    socket_.set_option(asio::socket_base::send_buffer_size(static_cast<int>(options.send_buffer_bytes)), ignored);
  }
}

void TcpSession::Start() {
  session_ = session::ClientSession::Create(client_, context_, [weak = weak_from_this()] {
    if (auto self = weak.lock()) self->WakeWriter();
  });
  ArmTimer();
  ContinueReading();
}

void TcpSession::Reject(proto::ErrorCode code, const std::string& message) {
  session::ClientProtocol::Refuse(code, message, true, reply_);
  Reply(Outcome::kReplyAndClose);
}

// Between messages: read the next one, unless the client's replies pile up
// (back-pressure: it reads them first) or the connection is ending.
void TcpSession::ContinueReading() {
  if (reading_ || close_after_writes_ || closed_) return;
  read_paused_ = Backlog() > limits::kReplyBacklogBytes;
  if (!read_paused_) ReadSome();
}

void TcpSession::ReadSome() {
  reading_ = true;
  socket_.async_read_some(asio::buffer(reader_.next_data(), reader_.next_size()),
                          [self = shared_from_this()](boost::system::error_code error, std::size_t count) {
                            self->OnRead(error, count);
                          });
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

// After a fatal Error, from ClientProtocol, the sim thread or a timeout: stop
// reading, send nothing more, close once the Error is out, or after
// kCloseLingerMs if the client does not read it.
void TcpSession::CloseAfterWrites(const proto::Envelope& error) {
  LOG_INFO("client " << client_ << " refused: " << error.error().message());
  close_after_writes_ = true;
  if (session_) session_->StopOffers();
  close_deadline_ = Clock::now() + std::chrono::milliseconds(limits::kCloseLingerMs);
  ArmTimer();
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

// Sets the timer for the earliest deadline unless it already fires sooner; a
// deadline that moved later is found when the timer fires (OnTimer).
void TcpSession::ArmTimer() {
  if (closed_) return;
  const Clock::time_point deadline = close_after_writes_ ? close_deadline_ : deadlines_.next();
  if (deadline >= timer_at_) return;
  timer_at_ = deadline;
  timer_.expires_at(deadline);  // cancels the earlier wait, if any
  timer_.async_wait([self = shared_from_this()](boost::system::error_code error) {
    if (error != asio::error::operation_aborted) self->OnTimer();
  });
}

void TcpSession::OnTimer() {
  timer_at_ = Clock::time_point::max();
  if (closed_) return;
  const auto now = Clock::now();
  if (close_after_writes_) {
    if (now < close_deadline_) return ArmTimer();
    LOG_INFO("client " << client_ << " did not read its fatal Error within " << limits::kCloseLingerMs
                       << " ms; closing its connection");
    return Close();
  }
  if (const auto expired = deadlines_.Check(now)) {
    return Reply(session::ClientProtocol::Refuse(expired->code, expired->message, true, reply_));
  }
  ArmTimer();
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
  if (!session_) return;
  session_->TakeReplies(offered_);
  for (const proto::Envelope& reply : offered_) {
    if (close_after_writes_) break;
    QueueEnvelope(reply);
    if (session::ClientProtocol::EndsConnection(reply)) CloseAfterWrites(reply);
  }
  offered_.clear();
  if (offered_.capacity() > 64) std::vector<proto::Envelope>().swap(offered_);  // a burst's slots go back
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
