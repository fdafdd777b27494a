// sim4cv::ShmClient, request side: messages into this client's request ring
// (single producer: this client; single consumer: the daemon) and responses
// out of its response ring (docs/protocol.md section 13.5).
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <thread>

#include "protocol/framing.h"
#include "../requests.h"
#include "protocol/shm_sync.h"
#include "sim4cv/shm_client.h"

namespace sim4cv {
namespace {

using Envelope = proto::Envelope;

// How long a sender waits for the daemon to free a request slot when all
// are in use before deciding the daemon is stuck.
constexpr auto kRingFullLimit = std::chrono::seconds(5);

}  // namespace

void ShmClient::SendEnvelope(const Envelope& envelope) {
  scratch_.clear();
  envelope.AppendToString(&scratch_);
  if (scratch_.size() > shm::kShmRequestDataBytes) {
    const auto* field = Envelope::descriptor()->FindFieldByNumber(envelope.kind_case());
    throw ShmError("the encoded " + (field ? field->name() : std::string("envelope")) + " is " +
                   std::to_string(scratch_.size()) + " bytes; a shared-memory request slot holds at most " +
                   std::to_string(shm::kShmRequestDataBytes) + " (shorten client_name, or use TCP)");
  }
  SendRaw(scratch_.data(), scratch_.size());
}

bool ShmClient::attached() const { return attached(true); }

bool ShmClient::attached(bool check_socket) const {
  if (!area_) return false;
  auto& closed = shm::AreaMap(area_).header().closed;
  if (shm::Atomic(closed).load(std::memory_order_acquire) != 0) return false;
  if (!check_socket) return true;
  // The daemon may also have died (SIGKILL): its end of the socket is then closed.
  pollfd socket{socket_, POLLIN, 0};
  if (poll(&socket, 1, 0) == 1 && (socket.revents & (POLLHUP | POLLERR | POLLRDHUP | POLLIN)) != 0) {
    char byte;
    if (recv(socket_, &byte, 1, MSG_DONTWAIT | MSG_PEEK) <= 0) return false;
  }
  return true;
}

void ShmClient::RequireAttached(bool check_socket) const {
  if (!frames_) throw ShmError("ShmClient::Open must succeed before sending");
  if (!area_) throw ConnectionError("this shared-memory client is not attached to sim4cvd (Open failed or was not called)");
  if (!attached(check_socket)) {
    throw ConnectionError("sim4cvd ended this shared-memory client's attachment to " + name_ +
                          " (it stopped, or the client was silent for its --shm-expiry-ms); send Hello to attach again");
  }
}

void ShmClient::SendRaw(const void* data, std::size_t size) {
  if (size > shm::kShmRequestDataBytes) {
    throw ShmError("message of " + std::to_string(size) + " bytes exceeds the " +
                   std::to_string(shm::kShmRequestDataBytes) + "-byte request slot");
  }
  RequireAttached(false);  // the flag only: no system call on the fast path
  const shm::AreaMap area(area_);
  shm::ShmAreaHeader& h = area.header();
  // Only free slots may be written: wait (briefly: the daemon drains within
  // microseconds) while the daemon has not yet taken the request a ring ago.
  const auto give_up = std::chrono::steady_clock::now() + kRingFullLimit;
  while (next_request_ - shm::Atomic(h.request_read).load(std::memory_order_acquire) >= shm::kShmRequestCapacity) {
    RequireAttached(true);
    if (std::chrono::steady_clock::now() > give_up) {
      throw ConnectionError("sim4cvd took none of this client's " + std::to_string(shm::kShmRequestCapacity) +
                            " queued shared-memory requests for " + std::to_string(kRingFullLimit.count()) + " s");
    }
    std::this_thread::yield();
  }
  shm::ShmRequestSlot& slot = area.request(next_request_);
  slot.size = static_cast<uint32_t>(size);
  std::memcpy(slot.data, data, size);
  // A plain release store publishes it: this client is the ring's only writer.
  shm::Atomic(h.request_write).store(++next_request_, std::memory_order_release);
  const uint64_t one = 1;
  [[maybe_unused]] const auto rang = write(doorbell_, &one, sizeof one);  // wakes the daemon
}

bool ShmClient::TryReadResponse(Envelope& reply) {
  if (!area_) return false;
  const shm::AreaMap area(area_);
  shm::ShmAreaHeader& h = area.header();
  for (int attempts = 0; attempts < 1000; ++attempts) {
    const uint64_t written = shm::Atomic(h.responses_written).load(std::memory_order_acquire);
    if (next_response_ >= written) return false;
    if (written - next_response_ > shm::kShmResponseDepth) {  // we fell a lap behind: the oldest are gone
      responses_lost_ += written - shm::kShmResponseDepth - next_response_;
      next_response_ = written - shm::kShmResponseDepth;
      DiscardLongResponsesBefore(next_response_);
    }
    shm::ShmResponseMessage& message = area.response(next_response_);
    const uint64_t before = shm::Atomic(message.sequence).load(std::memory_order_acquire);
    const uint32_t size = message.size;
    const bool on_socket = message.on_socket != 0;
    if (!on_socket) {
      scratch_.assign(reinterpret_cast<const char*>(message.data), std::min<uint32_t>(size, shm::kShmResponseDataBytes));
    }
    std::atomic_thread_fence(std::memory_order_acquire);
    const bool intact = before == shm::ResponseCompleteSequence(next_response_) &&
                        shm::Atomic(message.sequence).load(std::memory_order_relaxed) == before;
    if (!intact) continue;  // overwritten while we copied: re-evaluate
    const uint64_t k = next_response_++;
    if (on_socket ? ReceiveLongResponse(k, size, reply) : reply.ParseFromString(scratch_)) return true;
    ++responses_lost_;  // cannot happen with an intact copy of a daemon's response
  }
  return false;
}

void ShmClient::DiscardLongResponsesBefore(uint64_t k) {
  for (;;) {
    uint64_t tag = 0;
    const ssize_t got = recv(socket_, &tag, sizeof tag, MSG_DONTWAIT | MSG_PEEK);
    if (got != static_cast<ssize_t>(sizeof tag) || tag >= k) return;
    [[maybe_unused]] const auto dropped = recv(socket_, &tag, sizeof tag, MSG_DONTWAIT);  // the rest goes too
  }
}

bool ShmClient::ReceiveLongResponse(uint64_t k, uint32_t size, Envelope& reply) {
  if (size > shm::kShmSocketResponseBytes) return false;  // a daemon never announces one
  // Sized by this client's own bound, never by what the peer claims.
  long_response_.resize(shm::kShmSocketResponseHeaderBytes + shm::kShmSocketResponseBytes);
  for (;;) {
    iovec data{long_response_.data(), long_response_.size()};
    msghdr message{};
    message.msg_iov = &data;
    message.msg_iovlen = 1;
    // The daemon sent it before announcing it in the ring: it is here already.
    const ssize_t got = recvmsg(socket_, &message, MSG_DONTWAIT);
    if (got < static_cast<ssize_t>(shm::kShmSocketResponseHeaderBytes) || (message.msg_flags & MSG_TRUNC) != 0) {
      return false;
    }
    uint64_t tag = 0;
    std::memcpy(&tag, long_response_.data(), sizeof tag);
    if (tag < k) continue;  // its response was overwritten in the ring before this client read it
    const auto body = static_cast<std::size_t>(got) - shm::kShmSocketResponseHeaderBytes;
    return tag == k && body == size &&
           reply.ParseFromArray(long_response_.data() + shm::kShmSocketResponseHeaderBytes, static_cast<int>(body));
  }
}

bool ShmClient::NextResponse(Envelope& reply, Deadline deadline) {
  if (!frames_) throw ShmError("ShmClient::Open must succeed before receiving");
  if (!area_) throw ConnectionError("this shared-memory client is not attached to sim4cvd");
  auto& futex = shm::AreaMap(area_).header().response_futex;
  const auto start = std::chrono::steady_clock::now();
  const auto spin_end = start + spin_;
  for (;;) {
    const uint32_t seen = shm::Atomic(futex).load(std::memory_order_seq_cst);
    if (TryReadResponse(reply)) return true;
    // Every response was read: if the attachment is over, none will come.
    if (closed()) throw ConnectionError("sim4cvd stopped: the shared-memory ring " + name_ + " is closed");
    const auto now = std::chrono::steady_clock::now();
    // The flag says whether the daemon ended the attachment; after a while
    // also look at the socket, in case the daemon died without saying so.
    RequireAttached(now - start > std::chrono::milliseconds(100));
    if (now >= deadline) return false;
    if (now < spin_end) continue;
    // The daemon bumps the word and wakes after every response, and when it
    // ends the attachment. A short timeout also notices a daemon that died.
    const auto wait = std::min<Deadline::duration>(deadline - now, std::chrono::milliseconds(200));
    shm::FutexWait(futex, seen, std::chrono::duration_cast<std::chrono::nanoseconds>(wait).count());
  }
}

bool ShmClient::ReceiveReply(Envelope& reply, Duration timeout) {
  if (!pending_.empty()) {
    reply = std::move(pending_.front());
    pending_.pop_front();
    return true;
  }
  return NextResponse(reply, std::chrono::steady_clock::now() + timeout);
}

bool ShmClient::ReceiveKind(Envelope::KindCase kind, Envelope& out, Deadline deadline) {
  for (auto it = pending_.begin(); it != pending_.end(); ++it) {
    if (it->kind_case() != kind) continue;
    out = std::move(*it);
    pending_.erase(it);
    return true;
  }
  Envelope reply;
  while (NextResponse(reply, deadline)) {
    if (reply.kind_case() == kind) {
      out = std::move(reply);
      return true;
    }
    if (reply.has_error()) throw ServerError(reply.error().code(), reply.error().message(), reply.error().fatal());
    pending_.push_back(std::move(reply));  // e.g. a State for an earlier GetState
  }
  return false;
}

proto::Welcome ShmClient::Hello(const std::string& client_name, Duration timeout, uint32_t protocol_version) {
  const Deadline deadline = std::chrono::steady_clock::now() + timeout;
  const Envelope hello = detail::HelloRequest(client_name, protocol_version);
  if (frames_ && !attached()) Attach();  // the daemon ended the last attachment: a new one
  SendEnvelope(hello);
  Envelope reply;
  if (!ReceiveKind(Envelope::kWelcome, reply, deadline)) {
    throw ConnectionError("timed out after " + std::to_string(timeout.count()) +
                          " ms waiting for Welcome from sim4cvd over shared memory " + name_);
  }
  return reply.welcome();
}

void ShmClient::Subscribe(proto::Delivery delivery, Duration timeout) {
  // Whatever the ring carries: asking for more would be refused.
  std::vector<proto::Channel> channels;
  for (const auto channel : {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_MASK}) {
    if (carries(channel)) channels.push_back(channel);
  }
  channels.push_back(proto::CHANNEL_BOXES);
  Subscribe(delivery, channels, timeout);
}

void ShmClient::Subscribe(proto::Delivery delivery, const std::vector<proto::Channel>& channels, Duration timeout) {
  const Deadline deadline = std::chrono::steady_clock::now() + timeout;
  const Envelope request = detail::SubscribeRequest(camera(), channels, delivery, false);
  SendEnvelope(request);
  Envelope reply;
  if (!ReceiveKind(Envelope::kSubscribed, reply, deadline)) {
    throw ConnectionError("timed out after " + std::to_string(timeout.count()) +
                          " ms waiting for Subscribed over shared memory " + name_);
  }
}

void ShmClient::Step() {
  SendEnvelope(detail::StepRequest());
}

void ShmClient::SendTrackerOutput(uint64_t frame_id, float x, float y, float width, float height, float confidence) {
  SendEnvelope(detail::TrackerOutputRequest(frame_id, x, y, width, height, confidence));
}

void ShmClient::SendControls(uint32_t entity_id, float steering, float throttle, float brake) {
  SendEnvelope(detail::ControlsRequest(entity_id, steering, throttle, brake));
}

proto::State ShmClient::GetState(Duration timeout) {
  const Deadline deadline = std::chrono::steady_clock::now() + timeout;
  Envelope request;
  request.mutable_get_state();
  SendEnvelope(request);
  Envelope reply;
  if (!ReceiveKind(Envelope::kState, reply, deadline)) {
    throw ConnectionError("timed out after " + std::to_string(timeout.count()) +
                          " ms waiting for State over shared memory " + name_);
  }
  return reply.state();
}

}  // namespace sim4cv
