// Envelope.sequence over UDP: a Step, Controls or TrackerOutput is applied
// only if its sequence is greater than the last one applied from the same
// client, so a duplicated or late datagram can neither add a Step credit
// nor roll Controls back. Sequence 0 means "not sequenced": always applied
// and never remembered.
#pragma once

#include <cstdint>

namespace sim4cv::transport {

class SequenceFilter {
 public:
  // True if a datagram with `sequence` should be applied (and remembers it).
  bool Accept(uint64_t sequence) {
    if (sequence == 0) return true;
    if (sequence <= last_applied_) return false;
    last_applied_ = sequence;
    return true;
  }
  uint64_t last_applied() const { return last_applied_; }

 private:
  uint64_t last_applied_ = 0;
};

}  // namespace sim4cv::transport
