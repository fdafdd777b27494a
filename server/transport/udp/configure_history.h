// Configure over UDP is retried by the client with the same request_id until
// its answer arrives (docs/protocol.md 12.3), so the daemon must carry out a
// request once however often it comes: it remembers the last
// kRememberedConfigures request_ids of each client and, for a repeat, sends
// the remembered answer again (or nothing while the answer is pending).
// request_id 0 cannot be told apart and is always carried out.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "sim4cv.pb.h"

namespace sim4cv::transport {

class ConfigureHistory {
 public:
  static constexpr std::size_t kRememberedConfigures = 16;

  enum class Seen { kNew, kPending, kAnswered };

  // What is known of `request_id`; a new one (not 0) is remembered as
  // pending, forgetting the oldest. `answer` points at the encoded answer
  // of an answered one (valid until the next call).
  Seen Check(uint32_t request_id, const std::string** answer) {
    if (request_id == 0) return Seen::kNew;
    for (Entry& entry : entries_) {
      if (!entry.used || entry.request_id != request_id) continue;
      if (!entry.answered) return Seen::kPending;
      *answer = &entry.answer;
      return Seen::kAnswered;
    }
    Entry& entry = entries_[next_++ % kRememberedConfigures];
    entry = Entry{true, false, request_id, {}};
    return Seen::kNew;
  }

  // `reply`, about to be sent: if it answers a remembered Configure
  // (Configured, or an Error carrying its request_id), it is kept for repeats.
  void Answered(const proto::Envelope& reply) {
    uint32_t request_id = 0;
    if (reply.has_configured()) request_id = reply.configured().request_id();
    if (reply.has_error()) request_id = reply.error().request_id();
    if (request_id == 0) return;
    for (Entry& entry : entries_) {
      if (!entry.used || entry.answered || entry.request_id != request_id) continue;
      entry.answered = true;
      reply.SerializeToString(&entry.answer);
      return;
    }
  }

 private:
  struct Entry {
    bool used = false;
    bool answered = false;
    uint32_t request_id = 0;
    std::string answer;
  };
  std::array<Entry, kRememberedConfigures> entries_{};
  std::size_t next_ = 0;
};

}  // namespace sim4cv::transport
