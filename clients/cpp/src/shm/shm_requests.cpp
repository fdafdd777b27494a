// sim4cv::ShmClient, request side: messages into the multi-producer reply
// ring and responses out of this client's entry of the response area
// (docs/protocol.md section 13.5).
#include <algorithm>
#include <cstring>

#include "protocol/framing.h"
#include "../requests.h"
#include "protocol/shm_sync.h"
#include "sim4cv/shm_client.h"

namespace sim4cv {
namespace {

using Envelope = proto::Envelope;

// A slot still being written by the producer a full lap earlier is taken
// over after this many polls (that producer is dead or badly stalled).
constexpr int kTakeoverPolls = 20000;

}  // namespace

void ShmClient::SendEnvelope(const Envelope& envelope) {
  scratch_.clear();
  envelope.AppendToString(&scratch_);
  if (scratch_.size() > shm::kShmReplyDataBytes) {
    const auto* field = Envelope::descriptor()->FindFieldByNumber(envelope.kind_case());
    throw ShmError("the encoded " + (field ? field->name() : std::string("envelope")) + " is " +
                   std::to_string(scratch_.size()) + " bytes; a shared-memory reply slot holds at most " +
                   std::to_string(shm::kShmReplyDataBytes) + " (shorten client_name, or use TCP)");
  }
  SendRaw(scratch_.data(), scratch_.size());
}

void ShmClient::SendRaw(const void* data, std::size_t size) {
  if (!is_open()) throw ShmError("ShmClient::Open must succeed before sending");
  if (size > shm::kShmReplyDataBytes) {
    throw ShmError("message of " + std::to_string(size) + " bytes exceeds the " +
                   std::to_string(shm::kShmReplyDataBytes) + "-byte reply slot");
  }
  const shm::Mapped map(base_);
  shm::ShmHeader& h = map.header();
  const uint64_t ticket = shm::Atomic(h.reply_write).fetch_add(1, std::memory_order_acq_rel);
  shm::ShmReplySlot& slot = map.reply_slot(ticket);
  auto state = shm::Atomic(slot.state);
  uint64_t current = state.load(std::memory_order_acquire);
  for (int polls = 0;;) {
    // A later ticket already holds the slot: ours is the oldest, so it is the
    // one dropped (the daemon counts it when it reaches our ticket).
    if (current != 0 && shm::ReplyTicketOf(current) >= ticket) return;
    if ((current & 1) != 0 && ++polls < kTakeoverPolls) {
      current = state.load(std::memory_order_acquire);
      continue;
    }
    if (state.compare_exchange_weak(current, shm::ReplyWritingState(ticket), std::memory_order_acq_rel,
                                    std::memory_order_acquire)) {
      break;
    }
  }
  std::atomic_thread_fence(std::memory_order_release);  // the odd state before any byte
  slot.token = token_;
  slot.size = static_cast<uint32_t>(size);
  std::memcpy(slot.data, data, size);
  slot.checksum = shm::ReplyChecksum(token_, slot.data, slot.size);
  uint64_t expected = shm::ReplyWritingState(ticket);
  // Fails only if we were so slow that the daemon gave up on this ticket or a
  // producer a lap later took the slot; the message is then lost (and counted).
  state.compare_exchange_strong(expected, shm::ReplyCompleteState(ticket), std::memory_order_release,
                                std::memory_order_relaxed);
  shm::BumpAndWake(h.reply_futex, h.reply_sleeping);
}

int ShmClient::FindEntry() {
  const shm::Mapped map(base_);
  const uint32_t entries = map.header().response_entries;
  if (entry_ >= 0 && static_cast<uint32_t>(entry_) < entries) {
    shm::ShmResponseEntry& e = map.response_entry(static_cast<uint32_t>(entry_));
    if (shm::Atomic(e.token).load(std::memory_order_acquire) == token_ &&
        shm::Atomic(e.generation).load(std::memory_order_relaxed) == generation_) {
      return entry_;
    }
  }
  for (uint32_t i = 0; i < entries; ++i) {
    shm::ShmResponseEntry& e = map.response_entry(i);
    if (shm::Atomic(e.token).load(std::memory_order_acquire) != token_) continue;
    entry_ = static_cast<int>(i);  // a new assignment: its responses count from 0
    had_entry_ = true;
    generation_ = shm::Atomic(e.generation).load(std::memory_order_relaxed);
    next_response_ = 0;
    return entry_;
  }
  entry_ = -1;
  return -1;
}

bool ShmClient::TryReadResponse(Envelope& reply) {
  for (;;) {
    const int index = FindEntry();
    if (index < 0) return false;
    const shm::Mapped map(base_);
    shm::ShmResponseEntry& entry = map.response_entry(static_cast<uint32_t>(index));
    const uint64_t written = shm::Atomic(entry.written).load(std::memory_order_acquire);
    if (next_response_ >= written) return false;
    const uint64_t depth = map.header().response_depth;
    if (written - next_response_ > depth) {  // we fell a lap behind: the oldest are gone
      responses_lost_ += written - depth - next_response_;
      next_response_ = written - depth;
    }
    shm::ShmResponseMessage& message = map.response_message(static_cast<uint32_t>(index), next_response_);
    const uint64_t before = shm::Atomic(message.sequence).load(std::memory_order_acquire);
    const uint64_t message_index = message.index;
    const uint32_t size = std::min<uint32_t>(message.size, shm::kShmResponseDataBytes);
    scratch_.assign(reinterpret_cast<const char*>(message.data), size);
    std::atomic_thread_fence(std::memory_order_acquire);
    const bool intact = (before & 1) == 0 && shm::Atomic(message.sequence).load(std::memory_order_relaxed) == before &&
                        message_index == next_response_;
    if (!intact) continue;  // overwritten while we copied: re-evaluate
    // Still ours? An entry freed and reassigned meanwhile holds another client's responses.
    if (shm::Atomic(entry.token).load(std::memory_order_acquire) != token_ ||
        shm::Atomic(entry.generation).load(std::memory_order_relaxed) != generation_) {
      continue;  // FindEntry sees the change
    }
    ++next_response_;
    if (reply.ParseFromString(scratch_)) return true;
    ++responses_lost_;  // cannot happen with an intact copy of a daemon's response
  }
}

void ShmClient::WaitForResponse(uint32_t seen, Deadline deadline) {
  shm::ShmHeader& h = shm::Mapped(base_).header();
  const auto now = std::chrono::steady_clock::now();
  if (now >= deadline) return;
  shm::Atomic(h.response_waiters).fetch_add(1, std::memory_order_seq_cst);
  if (shm::Atomic(h.response_futex).load(std::memory_order_seq_cst) == seen) {
    shm::FutexWait(h.response_futex, seen,
                   std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - now).count());
  }
  shm::Atomic(h.response_waiters).fetch_sub(1, std::memory_order_seq_cst);
}

bool ShmClient::NextResponse(Envelope& reply, Deadline deadline) {
  if (!is_open()) throw ShmError("ShmClient::Open must succeed before receiving");
  shm::ShmHeader& h = shm::Mapped(base_).header();
  const auto spin_end = std::chrono::steady_clock::now() + spin_;
  for (;;) {
    const uint32_t seen = shm::Atomic(h.response_futex).load(std::memory_order_seq_cst);
    if (TryReadResponse(reply)) return true;
    if (closed()) throw ConnectionError("sim4cvd stopped: the shared-memory ring " + name_ + " is closed");
    if (entry_ < 0 && had_entry_) {
      had_entry_ = false;
      throw ConnectionError("sim4cvd disconnected this shared-memory client after " + std::to_string(h.expiry_ms) +
                            " ms without a message (its --shm-expiry-ms); send Hello again");
    }
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return false;
    if (now < spin_end) continue;
    WaitForResponse(seen, deadline);
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
  had_entry_ = false;  // a Hello may legitimately find our old entry gone
  SendEnvelope(hello);
  Envelope reply;
  if (!ReceiveKind(Envelope::kWelcome, reply, deadline)) {
    throw ConnectionError("timed out after " + std::to_string(timeout.count()) +
                          " ms waiting for Welcome from sim4cvd over shared memory " + name_ +
                          " (is the daemon serving its maximum number of shared-memory clients?)");
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
