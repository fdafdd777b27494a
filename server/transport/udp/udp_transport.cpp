#include "server/transport/udp/udp_transport.h"

#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <thread>
#include <unordered_map>
#include <vector>

#include "protocol/framing.h"
#include "server/common/check.h"
#include "server/common/diagnostics.h"
#include "server/common/limits.h"
#include "server/transport/udp/udp_counters.h"
#include "server/transport/udp/udp_peer.h"

namespace sim4cv::transport {
namespace {

using Clock = std::chrono::steady_clock;
using Outcome = session::ClientProtocol::Outcome;
using Kind = proto::Envelope::KindCase;

// Replies to addresses that are not registered (Welcome to a new Hello,
// refused Hellos, NOT_HANDSHAKEN): a burst of 50, then 50 per second in all,
// so spoofed or garbage datagrams cannot make the daemon a reflector.
constexpr double kStrangerRepliesPerSecond = 50;
constexpr double kStrangerReplyBurst = 50;
// Receive batches per loop turn before frames get their turn again.
constexpr int kReceiveBatchesPerTurn = 8;
// Chunks handed to the kernel per sendmmsg call.
constexpr std::size_t kSendBatch = 64;
constexpr auto kDropLogInterval = std::chrono::seconds(5);

class UdpTransport : public Transport {
 public:
  explicit UdpTransport(const UdpOptions& options)
      : options_(options),
        socket_(options.bind_address, options.port),
        wakeup_(std::make_shared<Wakeup>()),
        stranger_limit_(kStrangerRepliesPerSecond, kStrangerReplyBurst) {
    FrameChunker validate(options.max_datagram_bytes);  // throws naming a bad --udp-datagram-bytes
    SIM4CV_THROW_UNLESS(options.expiry_ms > 0, "--udp-expiry-ms is 0; it must be at least 1");
    SIM4CV_THROW_UNLESS(options.max_clients > 0, "--max-clients is 0; it must be at least 1");
    sweep_interval_ = std::clamp(std::chrono::milliseconds(options.expiry_ms / 4), std::chrono::milliseconds(5),
                                 std::chrono::milliseconds(1000));
  }

  ~UdpTransport() override { Stop(); }

  proto::TransportInfo info() const override {
    proto::TransportInfo info;
    info.set_kind(proto::TRANSPORT_KIND_UDP);
    info.set_address(std::to_string(socket_.port()));
    return info;
  }

  std::string listening_field() const override { return "udp=" + std::to_string(socket_.port()); }

  void Start(const session::ServerContext& context) override {
    context_ = &context;
    LOG_INFO("UDP on port " << socket_.port() << ": datagrams up to " << options_.max_datagram_bytes
                            << " bytes, registrations expire after " << options_.expiry_ms
                            << " ms of silence, kernel receive buffer " << socket_.receive_buffer_bytes() << " bytes");
    thread_ = std::thread([this] { Run(); });
  }

  void Stop() override {
    if (!thread_.joinable()) return;
    stop_ = true;
    wakeup_->Notify();
    thread_.join();
    for (auto& [address, peer] : peers_) peer->Close(true);
    peers_.clear();
    counters_.Flush(context_->counters);
  }

 private:
  void Run() {
    auto next_sweep = Clock::now() + sweep_interval_;
    auto next_drop_log = Clock::now() + kDropLogInterval;
    bool blocked = false;  // the socket's send buffer was full
    while (!stop_) {
      std::array<pollfd, 2> fds = {pollfd{socket_.fd(), static_cast<short>(POLLIN | (blocked ? POLLOUT : 0)), 0},
                                   pollfd{wakeup_->fd(), POLLIN, 0}};
      const auto wait = std::chrono::ceil<std::chrono::milliseconds>(next_sweep - Clock::now());
      poll(fds.data(), fds.size(), static_cast<int>(std::max<int64_t>(0, wait.count())));
      if (fds[1].revents != 0) wakeup_->Clear();
      if (stop_) break;
      auto now = Clock::now();
      if (fds[0].revents & POLLIN) ReceiveDatagrams(now);
      SendOfferedReplies(now);
      blocked = !SendFrames();
      now = Clock::now();
      if (now >= next_sweep) {
        Expire(now);
        next_sweep = now + sweep_interval_;
      }
      counters_.Flush(context_->counters);
      if (now >= next_drop_log) {
        LogDrops();
        next_drop_log = now + kDropLogInterval;
      }
    }
  }

  void ReceiveDatagrams(Clock::time_point now) {
    for (int turn = 0; turn < kReceiveBatchesPerTurn; ++turn) {
      const std::size_t count = batch_.Receive(socket_.fd());
      counters_.Add(UdpCounter::kReceiveBufferOverflow, batch_.kernel_drops() - kernel_drops_);
      kernel_drops_ = batch_.kernel_drops();
      for (std::size_t i = 0; i < count; ++i) {
        HandleDatagram(batch_.address(i), batch_.data(i), batch_.size(i), batch_.truncated(i), now);
      }
      if (count < DatagramBatch::kDatagrams) return;
    }
  }

  void HandleDatagram(const PeerAddress& from, const uint8_t* data, std::size_t size, bool truncated,
                      Clock::time_point now) {
    counters_.Add(UdpCounter::kDatagramsReceived);
    const auto found = peers_.find(from);
    UdpPeer* peer = found == peers_.end() ? nullptr : found->second.get();
    if (peer) peer->Heard(now);  // any datagram from a registered address keeps it registered
    if (truncated) {
      counters_.Add(UdpCounter::kDatagramsTruncated);
      return;
    }
    if (!request_.ParseFromArray(data, static_cast<int>(size))) {
      counters_.Add(UdpCounter::kMalformed);
      if (peer) {
        session::ClientProtocol::Refuse(
            proto::ERROR_CODE_MALFORMED_MESSAGE,
            "the " + std::to_string(size) + "-byte datagram is not a valid Envelope; it was dropped", false, reply_);
        SendError(*peer, now);
      }
      return;
    }
    if (request_.has_frame_chunk()) {  // only the daemon sends chunks
      counters_.Add(UdpCounter::kClientFrameChunk);
      return;
    }
    if (peer) {
      Dispatch(*peer, now);
    } else {
      HandleStranger(from, now);
    }
  }

  // A datagram from an address that is not registered: only Hello registers.
  void HandleStranger(const PeerAddress& from, Clock::time_point now) {
    if (!request_.has_hello()) {
      counters_.Add(UdpCounter::kUnregisteredSender);
      if (request_.kind_case() == Kind::KIND_NOT_SET) return;  // a keep-alive that came too late: no answer
      session::ClientProtocol::Refuse(proto::ERROR_CODE_NOT_HANDSHAKEN,
                                      "UDP address " + from.ToString() +
                                          " is not registered (no Hello yet, or its registration lapsed after " +
                                          std::to_string(options_.expiry_ms) + " ms of silence); send Hello first",
                                      true, reply_);
      ReplyToStranger(from, now);
      return;
    }
    if (peers_.size() >= options_.max_clients) {
      counters_.Add(UdpCounter::kTooManyClients);
      session::ClientProtocol::Refuse(proto::ERROR_CODE_TOO_MANY_CLIENTS,
                                      "the daemon already serves " + std::to_string(peers_.size()) +
                                          " UDP clients (daemon flag --max-clients); try again after one expires",
                                      true, reply_);
      ReplyToStranger(from, now);
      return;
    }
    auto peer =
        std::make_shared<UdpPeer>(session::NewClientId(), from, *context_, wakeup_, options_.max_datagram_bytes, now);
    peer->Start();
    peer->protocol().Handle(request_, reply_);
    if (!reply_.has_welcome()) {
      peer->Close(false);  // refused (e.g. VERSION_MISMATCH): never registered
      ReplyToStranger(from, now);
      return;
    }
    counters_.Add(UdpCounter::kRegistrations);
    LOG_INFO("client " << peer->client() << " registered over UDP from " << from.ToString());
    peers_.emplace(from, std::move(peer));
    ReplyToStranger(from, now);
  }

  void Dispatch(UdpPeer& peer, Clock::time_point now) {
    switch (request_.kind_case()) {
      case Kind::KIND_NOT_SET:
        return;  // keep-alive
      case Kind::kHello:
        if (request_.hello().protocol_version() == wire::kProtocolVersion) {
          // A repeated Hello: its Welcome may have been lost. Same answer, nothing else changes.
          reply_.Clear();
          session::ClientProtocol::FillWelcome(*context_, peer.client(), *reply_.mutable_welcome());
          if (Limit(peer, now)) SendReplyTo(peer);
          return;
        }
        break;
      case Kind::kStep:
      case Kind::kControls:
      case Kind::kTrackerOutput:
        if (!peer.sequence().Accept(request_.sequence())) {
          counters_.Add(UdpCounter::kOutOfOrder);
          return;
        }
        break;
      case Kind::kGetStats:
        counters_.Flush(context_->counters);
        break;
      case Kind::kConfigure:
        if (RepeatedConfigure(peer, now)) return;
        break;
      default:
        break;
    }
    if (peer.protocol().Handle(request_, reply_) == Outcome::kNoReply) return;
    if (!Answer(peer, now)) Remove(peer.address());
  }

  // A retried Configure (its request_id seen lately) is not carried out
  // again: its remembered answer goes out again, within the peer's reply
  // rate limit, or nothing while the sim thread has not answered yet.
  bool RepeatedConfigure(UdpPeer& peer, Clock::time_point now) {
    const std::string* answer = nullptr;
    const auto seen = peer.configures().Check(request_.configure().request_id(), &answer);
    if (seen == ConfigureHistory::Seen::kNew) return false;
    counters_.Add(UdpCounter::kConfigureRepeated);
    if (seen == ConfigureHistory::Seen::kAnswered && Limit(peer, now)) {
      reply_bytes_ = *answer;
      SendEncodedTo(peer);
    }
    return true;
  }

  // What the sim thread offered each peer (ClientLink::OfferReply), each
  // sent as ClientProtocol's replies are; a fatal Error unregisters its peer.
  void SendOfferedReplies(Clock::time_point now) {
    for (auto it = peers_.begin(); it != peers_.end();) {
      if (SendRepliesOfferedTo(*it->second, now)) {
        ++it;
        continue;
      }
      it->second->Close(true);
      it = peers_.erase(it);
    }
  }

  // False once a fatal Error went out: the caller unregisters the peer, and
  // the replies offered after that Error are dropped with it.
  bool SendRepliesOfferedTo(UdpPeer& peer, Clock::time_point now) {
    peer.TakeOfferedReplies(offered_);
    for (proto::Envelope& offered : offered_) {
      reply_.Swap(&offered);
      if (!Answer(peer, now)) return false;
    }
    return true;
  }

  // Sends reply_ to a registered peer, an Error within the peer's rate limit.
  // False if it was a fatal Error: the caller unregisters the peer.
  bool Answer(UdpPeer& peer, Clock::time_point now) {
    peer.configures().Answered(reply_);
    if (reply_.has_error()) {
      SendError(peer, now);
    } else {
      SendReplyTo(peer);
    }
    if (!session::ClientProtocol::EndsConnection(reply_)) return true;
    counters_.Add(UdpCounter::kClosedByError);
    LOG_INFO("client " << peer.client() << " over UDP refused and unregistered: " << reply_.error().message());
    return false;
  }

  bool Limit(UdpPeer& peer, Clock::time_point now) {
    if (peer.error_limit().Allow(now)) return true;
    counters_.Add(UdpCounter::kRepliesRateLimited);
    return false;
  }

  void SendError(UdpPeer& peer, Clock::time_point now) {
    if (!Limit(peer, now)) return;
    counters_.Add(UdpCounter::kErrorsSent);
    SendReplyTo(peer);
  }

  void ReplyToStranger(const PeerAddress& to, Clock::time_point now) {
    if (!stranger_limit_.Allow(now)) {
      counters_.Add(UdpCounter::kRepliesRateLimited);
      return;
    }
    if (reply_.has_error()) counters_.Add(UdpCounter::kErrorsSent);
    SendReply(to);
  }

  // reply_ as one datagram to an address that is not a registered peer.
  // One that meets a full send buffer is dropped (and counted): a stranger's
  // retry asks again.
  void SendReply(const PeerAddress& to) {
    reply_bytes_.clear();
    reply_.AppendToString(&reply_bytes_);
    if (SendDatagram(to, reply_bytes_) < 0 && FullBuffer()) counters_.Add(UdpCounter::kSendFailed);
  }

  // reply_ to a registered peer. Frames fill the send buffer to the brim, so
  // a reply may meet it full: it then waits in the peer's unsent queue
  // (bounded like the sim thread's replies, kMaxOfferedReplyBytes) and goes
  // before that peer's next frame chunk, so no reply is lost to a burst of
  // frames and none is overtaken by a later frame.
  void SendReplyTo(UdpPeer& peer) {
    reply_bytes_.clear();
    reply_.AppendToString(&reply_bytes_);
    SendEncodedTo(peer);
  }

  // reply_bytes_ to a registered peer (SendReplyTo).
  void SendEncodedTo(UdpPeer& peer) {
    if (peer.unsent_replies().empty() && SendDatagram(peer.address(), reply_bytes_) >= 0) return;
    if (!peer.unsent_replies().empty() || FullBuffer()) {
      if (peer.unsent_bytes() + reply_bytes_.size() > limits::kMaxOfferedReplyBytes) {
        counters_.Add(UdpCounter::kSendFailed);  // the client reads nothing: it retries, or expires
        return;
      }
      peer.unsent_bytes() += reply_bytes_.size();
      peer.unsent_replies().push_back(reply_bytes_);
    }
  }

  // Sends what waits in the peer's unsent queue; false while the buffer is full.
  bool FlushUnsent(UdpPeer& peer) {
    auto& unsent = peer.unsent_replies();
    while (!unsent.empty()) {
      if (SendDatagram(peer.address(), unsent.front()) < 0 && FullBuffer()) return false;
      peer.unsent_bytes() -= unsent.front().size();
      unsent.pop_front();
    }
    return true;
  }

  // Whether the last send failed only because the socket's buffer was full.
  static bool FullBuffer() { return errno == EAGAIN || errno == EWOULDBLOCK; }

  // One datagram. Failures other than a full buffer are counted here (the
  // reply is lost); a full buffer is the caller's to count or queue.
  ssize_t SendDatagram(const PeerAddress& to, const std::string& bytes) {
    const ssize_t sent = sendto(socket_.fd(), bytes.data(), bytes.size(), MSG_DONTWAIT,
                                reinterpret_cast<const sockaddr*>(&to.storage), to.length);
    if (sent < 0) {
      const int error = errno;
      if (!FullBuffer()) counters_.Add(UdpCounter::kSendFailed);
      LOG_DEBUG("UDP reply to " << to.ToString() << " failed: " << std::strerror(error));
      errno = error;
    }
    return sent;
  }

  // Sends frames round-robin, one batch of chunks per client per round.
  // False if the socket's send buffer is full (wait for POLLOUT).
  bool SendFrames() {
    bool progress = true;
    while (progress) {
      progress = false;
      for (auto& [address, peer] : peers_) {
        if (!FlushUnsent(*peer)) return false;
        if (!peer->NextFrame()) continue;
        if (!SendChunks(*peer)) return false;
        progress = true;
      }
    }
    return true;
  }

  // One sendmmsg of the current frame's next chunks. False if the send buffer is full.
  bool SendChunks(UdpPeer& peer) {
    const FrameChunker& chunker = peer.chunker();
    const uint32_t first = peer.next_chunk();
    const std::size_t count = std::min<std::size_t>(kSendBatch, chunker.chunk_count() - first);
    for (std::size_t i = 0; i < count; ++i) {
      msghdr& message = send_headers_[i].msg_hdr;
      message = {};
      message.msg_name = const_cast<sockaddr_storage*>(&peer.address().storage);
      message.msg_namelen = peer.address().length;
      message.msg_iov = send_iovecs_[i].data();
      message.msg_iovlen = chunker.Build(first + static_cast<uint32_t>(i), chunk_headers_[i], send_iovecs_[i].data());
    }
    int sent = -1;
    do {
      sent = sendmmsg(socket_.fd(), send_headers_.data(), static_cast<unsigned>(count), 0);
    } while (sent < 0 && errno == EINTR);
    if (sent < 0) {
      if (FullBuffer()) return false;
      // E.g. ENOBUFS: this frame is lost for this client, the next one may fare better.
      counters_.Add(UdpCounter::kSendFailed);
      LOG_DEBUG("UDP frame to " << peer.address().ToString() << " failed: " << std::strerror(errno));
      peer.AbandonFrame();
      return true;
    }
    counters_.Add(UdpCounter::kChunksSent, static_cast<uint64_t>(sent));
    if (peer.Advance(static_cast<uint32_t>(sent))) counters_.Add(UdpCounter::kFramesSent);
    return true;
  }

  void Expire(Clock::time_point now) {
    const auto expiry = std::chrono::milliseconds(options_.expiry_ms);
    for (auto it = peers_.begin(); it != peers_.end();) {
      UdpPeer& peer = *it->second;
      if (now - peer.last_heard() <= expiry) {
        ++it;
        continue;
      }
      counters_.Add(UdpCounter::kExpired);
      // Counted before the sim thread hears of it: stats read after the lockstep moves on include it.
      counters_.Flush(context_->counters);
      LOG_INFO("client " << peer.client() << " ('" << peer.protocol().client_name() << "') over UDP from "
                         << peer.address().ToString() << " expired after " << options_.expiry_ms << " ms of silence");
      peer.Close(true);
      it = peers_.erase(it);
    }
  }

  void Remove(const PeerAddress& address) {
    const auto found = peers_.find(address);
    if (found == peers_.end()) return;
    const std::shared_ptr<UdpPeer> peer = found->second;  // `address` may live in it
    peers_.erase(found);
    peer->Close(true);
  }

  // One log line per interval in which datagrams were dropped.
  void LogDrops() {
    std::string line;
    for (const auto& [counter, name] : {std::pair{UdpCounter::kMalformed, "malformed"},
                                        {UdpCounter::kUnregisteredSender, "unregistered_sender"},
                                        {UdpCounter::kClientFrameChunk, "client_frame_chunk"},
                                        {UdpCounter::kOutOfOrder, "out_of_order"},
                                        {UdpCounter::kDatagramsTruncated, "datagrams_truncated"},
                                        {UdpCounter::kReceiveBufferOverflow, "receive_buffer_overflow"},
                                        {UdpCounter::kRepliesRateLimited, "replies_rate_limited"}}) {
      const uint64_t total = counters_.total(counter);
      uint64_t& logged = logged_drops_[static_cast<std::size_t>(counter)];
      if (total == logged) continue;
      line += " udp." + std::string(name) + "=" + std::to_string(total) + " (+" + std::to_string(total - logged) + ")";
      logged = total;
    }
    if (!line.empty()) LOG_INFO("UDP datagrams dropped so far:" << line);
  }

  UdpOptions options_;
  UdpSocket socket_;
  std::shared_ptr<Wakeup> wakeup_;
  std::chrono::milliseconds sweep_interval_{};
  const session::ServerContext* context_ = nullptr;
  std::thread thread_;
  std::atomic<bool> stop_{false};

  // The transport's thread only.
  std::unordered_map<PeerAddress, std::shared_ptr<UdpPeer>, PeerAddressHash> peers_;
  RateLimiter stranger_limit_;
  UdpCounters counters_;
  std::array<uint64_t, static_cast<std::size_t>(UdpCounter::kCount)> logged_drops_{};
  uint32_t kernel_drops_ = 0;
  DatagramBatch batch_;
  proto::Envelope request_;
  proto::Envelope reply_;
  std::vector<proto::Envelope> offered_;  // reused: one peer's replies from the sim thread
  std::string reply_bytes_;
  std::array<mmsghdr, kSendBatch> send_headers_{};
  std::array<std::array<iovec, FrameChunker::kMaxIovecs>, kSendBatch> send_iovecs_{};
  std::array<FrameChunker::Header, kSendBatch> chunk_headers_{};
};

}  // namespace

std::unique_ptr<Transport> MakeUdpTransport(const UdpOptions& options) {
  return std::make_unique<UdpTransport>(options);
}

}  // namespace sim4cv::transport
