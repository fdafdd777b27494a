// Wire framing shared by the daemon and C++ clients: on a stream transport
// every Envelope is preceded by its size as a 4-byte little-endian uint32.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sim4cv::wire {

// The protocol version this build speaks (Hello/Welcome.protocol_version).
inline constexpr uint32_t kProtocolVersion = 1;

// Bytes of the length prefix before each envelope on TCP.
inline constexpr std::size_t kLengthPrefixBytes = 4;

// Clients' default upper bound on one envelope they receive (a frame with every
// channel at 1920x1080 is about 19 MB); larger prefixes are refused. What the
// daemon accepts from clients is limits::kDefaultMaxMessageBytes (--max-message-bytes).
inline constexpr uint32_t kDefaultMaxMessageBytes = 64u << 20;

// Writes `size` little-endian into out[0..3].
void EncodeLengthPrefix(uint32_t size, uint8_t* out);

// Reads the little-endian size from in[0..3].
uint32_t DecodeLengthPrefix(const uint8_t* in);

}  // namespace sim4cv::wire
