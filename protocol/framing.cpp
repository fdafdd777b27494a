#include "protocol/framing.h"

namespace sim4cv::wire {

void EncodeLengthPrefix(uint32_t size, uint8_t* out) {
  // Byte by byte so the wire order does not depend on the host's endianness.
  for (std::size_t i = 0; i < kLengthPrefixBytes; ++i) out[i] = static_cast<uint8_t>(size >> (8 * i));
}

uint32_t DecodeLengthPrefix(const uint8_t* in) {
  uint32_t size = 0;
  for (std::size_t i = 0; i < kLengthPrefixBytes; ++i) size |= static_cast<uint32_t>(in[i]) << (8 * i);
  return size;
}

}  // namespace sim4cv::wire
