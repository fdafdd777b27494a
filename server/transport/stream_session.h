// What a TCP connection and a WebSocket have in common as client sessions
// (CRTP base of TcpSession and WsSession): one timer for ConnectionDeadlines
// and the linger after a fatal Error, back-pressure on reading, the sim
// thread's replies taken from the session::ClientSession, and the one
// wake-up of the writer the sim thread posts. The derived class moves the
// bytes: Session::ReadSome, Reply, QueueEnvelope, PumpWrites, Close, and
// Session::CanRead() (false until a WebSocket's upgrade completed).
#pragma once

// clang-format off
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
// clang-format on
#include <atomic>
#include <boost/asio.hpp>
#include <chrono>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "server/common/diagnostics.h"
#include "server/common/limits.h"
#include "server/session/client_session.h"
#include "server/transport/tcp/connection_deadlines.h"

namespace sim4cv::transport {

template <typename Session>
class StreamSession {
 protected:
  using Clock = std::chrono::steady_clock;

  // `what`: how the log names the link ("connection", "WebSocket").
  StreamSession(const boost::asio::any_io_executor& executor, session::ClientId client, const TcpTimeouts& timeouts,
                const char* what)
      : client_(client), deadlines_(timeouts, Clock::now()), timer_(executor), what_(what) {}

  // The client's session; its offers wake this one's writer.
  void CreateSession(const session::ServerContext& context) {
    session_ = session::ClientSession::Create(client_, context, [weak = self().weak_from_this()] {
      if (auto alive = weak.lock()) alive->WakeWriter();
    });
  }

  // Between messages: read the next one, unless the client's replies pile up
  // (back-pressure: it reads them first) or the link is ending.
  void ContinueReading() {
    if (reading_ || close_after_writes_ || closed_ || !self().CanRead()) return;
    read_paused_ = Backlog() > limits::kReplyBacklogBytes;
    if (!read_paused_) self().ReadSome();
  }

  // After a fatal Error, from ClientProtocol, the sim thread or a timeout:
  // read no more, send nothing after it, close once it is out, or after
  // kCloseLingerMs if the client does not take it.
  void StopAfter(const proto::Envelope& error) {
    LOG_INFO("client " << client_ << " refused: " << error.error().message());
    close_after_writes_ = true;
    if (session_) session_->StopOffers();
    close_deadline_ = Clock::now() + std::chrono::milliseconds(limits::kCloseLingerMs);
    ArmTimer();
  }

  // Bytes of replies waiting to be sent: queued here, in flight, and offered by the sim thread.
  std::size_t Backlog() const { return queued_bytes_ + (session_ ? session_->reply_bytes() : 0); }

  // Sets the timer for the earliest deadline unless it already fires sooner; a
  // deadline that moved later is found when the timer fires (OnTimer).
  void ArmTimer() {
    if (closed_) return;
    const Clock::time_point deadline = close_after_writes_ ? close_deadline_ : deadlines_.next();
    if (deadline >= timer_at_) return;
    timer_at_ = deadline;
    timer_.expires_at(deadline);  // cancels the earlier wait, if any
    timer_.async_wait([alive = self().shared_from_this()](boost::system::error_code error) {
      if (error != boost::asio::error::operation_aborted) alive->OnTimer();
    });
  }

  void OnTimer() {
    timer_at_ = Clock::time_point::max();
    if (closed_) return;
    const auto now = Clock::now();
    if (close_after_writes_) {
      if (now < close_deadline_) return ArmTimer();
      LOG_INFO("client " << client_ << " did not take its fatal Error within " << limits::kCloseLingerMs
                         << " ms; closing its " << what_);
      return self().Close();
    }
    if (const auto expired = deadlines_.Check(now)) {
      return self().Reply(session::ClientProtocol::Refuse(expired->code, expired->message, true, reply_));
    }
    ArmTimer();
  }

  // Sim thread. One pending wake-up is enough however many offers arrive before it runs.
  void WakeWriter() {
    if (!pump_posted_.exchange(true)) {
      boost::asio::post(timer_.get_executor(), [alive = self().shared_from_this()] {
        alive->pump_posted_ = false;
        alive->PumpWrites();
      });
    }
  }

  // Queues the sim thread's replies behind ClientProtocol's; nothing after a fatal Error.
  void TakeOfferedReplies() {
    if (!session_) return;
    session_->TakeReplies(offered_);
    for (const proto::Envelope& reply : offered_) {
      if (close_after_writes_) break;
      self().QueueEnvelope(reply);
      if (session::ClientProtocol::EndsConnection(reply)) self().CloseAfterWrites(reply);
    }
    offered_.clear();
    if (offered_.capacity() > 64) std::vector<proto::Envelope>().swap(offered_);  // a burst's slots go back
  }

  session::ClientId client_;
  std::shared_ptr<session::ClientSession> session_;  // null for a client refused before its session began
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
  std::size_t queued_bytes_ = 0;          // replies_ and reply_in_flight_
  std::vector<proto::Envelope> offered_;  // reused: the sim thread's replies taken from the session
  session::FrameRef frame_in_flight_;
  bool writing_ = false;
  bool close_after_writes_ = false;
  bool closed_ = false;
  std::atomic<bool> pump_posted_{false};

 private:
  Session& self() { return static_cast<Session&>(*this); }
  const char* what_;
};

}  // namespace sim4cv::transport
