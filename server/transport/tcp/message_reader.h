// Reassembles one length-prefixed Envelope at a time from a byte stream, in
// the pieces the socket delivers. Memory follows what arrived, never what a
// prefix announced: a 4-byte prefix alone allocates nothing, and the body
// grows at most one read piece (limits::kReadChunkBytes) ahead of the bytes
// received (docs/reliability.md, finding 4). A body buffer grown past
// limits::kKeptBufferBytes is given back when the next message starts.
// No I/O here: the TCP session asks where to read to and says how much came.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace sim4cv::transport {

class MessageReader {
 public:
  enum class Status {
    kNeedMore,  // read more into Next()
    kComplete,  // body() holds a whole message
    kTooLarge,  // the prefix announced more than the limit; announced() says how much
  };

  explicit MessageReader(uint32_t max_message_bytes) : max_message_bytes_(max_message_bytes) {}

  // Where the next read should put its bytes, and at most how many.
  // Never empty while a message is incomplete.
  uint8_t* next_data();
  std::size_t next_size() const;

  // `count` bytes were written at next_data().
  Status Advance(std::size_t count);

  // Forgets the message just handled (after kComplete): the next byte starts
  // a new one. Gives the body's memory back if it grew large.
  void Next();

  // Whether any byte of the current message (prefix included) has arrived.
  bool started() const { return prefix_got_ > 0; }
  uint32_t announced() const { return announced_; }
  const std::string& body() const { return body_; }
  // The body buffer's capacity: what this reader holds.
  std::size_t held_bytes() const { return body_.capacity(); }

 private:
  bool prefix_complete() const;

  const uint32_t max_message_bytes_;
  uint8_t prefix_[4] = {};
  std::size_t prefix_got_ = 0;
  uint32_t announced_ = 0;
  std::string body_;
  std::size_t body_got_ = 0;  // bytes of body_ that arrived; body_ may be one piece longer
};

}  // namespace sim4cv::transport
