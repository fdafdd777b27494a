#include "server/transport/tcp/message_reader.h"

#include <algorithm>

#include "protocol/framing.h"
#include "server/common/limits.h"

namespace sim4cv::transport {

bool MessageReader::prefix_complete() const { return prefix_got_ == wire::kLengthPrefixBytes; }

uint8_t* MessageReader::next_data() {
  if (!prefix_complete()) return prefix_ + prefix_got_;
  // Room for one more piece, no more: the buffer grows with what arrived.
  const std::size_t piece = std::min<std::size_t>(announced_ - body_got_, limits::kReadChunkBytes);
  if (body_.size() < body_got_ + piece) body_.resize(body_got_ + piece);
  return reinterpret_cast<uint8_t*>(body_.data()) + body_got_;
}

std::size_t MessageReader::next_size() const {
  if (!prefix_complete()) return wire::kLengthPrefixBytes - prefix_got_;
  return std::min<std::size_t>(announced_ - body_got_, limits::kReadChunkBytes);
}

MessageReader::Status MessageReader::Advance(std::size_t count) {
  if (!prefix_complete()) {
    prefix_got_ += count;
    if (!prefix_complete()) return Status::kNeedMore;
    announced_ = wire::DecodeLengthPrefix(prefix_);
    if (announced_ > max_message_bytes_) return Status::kTooLarge;
    body_.clear();
    body_got_ = 0;
  } else {
    body_got_ += count;
  }
  if (body_got_ < announced_) return Status::kNeedMore;
  body_.resize(announced_);
  return Status::kComplete;
}

void MessageReader::Next() {
  prefix_got_ = 0;
  announced_ = 0;
  body_got_ = 0;
  body_.clear();
  if (body_.capacity() > limits::kKeptBufferBytes) std::string().swap(body_);
}

}  // namespace sim4cv::transport
