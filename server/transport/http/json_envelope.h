// Envelopes as JSON text, the WebSocket transport's encoding (docs/protocol.md,
// "WebSocket"): protobuf's canonical JSON mapping with the .proto's own field
// names, so a page needs no protobuf library and reads the same names as the
// docs.
#pragma once

#include <string>
#include <string_view>

#include "sim4cv.pb.h"

namespace sim4cv::transport {

// Parses `text` into `envelope` (cleared first). Returns "" on success, else
// what is wrong, for the Error a client gets: protobuf's own words (the
// unknown field, the bad value), cut to a bounded length.
std::string EnvelopeFromJson(std::string_view text, proto::Envelope& envelope);

// `envelope` as JSON text into `out` (replaced): field names as in the
// .proto, enums by name, 64-bit integers as strings (the JSON mapping's rule).
void EnvelopeToJson(const proto::Envelope& envelope, std::string& out);

}  // namespace sim4cv::transport
