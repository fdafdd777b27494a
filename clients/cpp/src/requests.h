// The client requests every transport's client sends, built in one place so
// the TCP, UDP and shared-memory clients cannot drift apart.
#pragma once

#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "sim4cv.pb.h"

namespace sim4cv::detail {

// protocol_version 0 means this build's version.
proto::Envelope HelloRequest(const std::string& client_name, uint32_t protocol_version);
proto::Envelope SubscribeRequest(const std::string& camera, const std::vector<proto::Channel>& channels,
                                 proto::Delivery delivery, bool with_state);
proto::Envelope StepRequest();
proto::Envelope TrackerOutputRequest(uint64_t frame_id, float x, float y, float width, float height, float confidence);
proto::Envelope ControlsRequest(uint32_t entity_id, float steering, float throttle, float brake);

// Moves the oldest queued envelope of `kind` into `out`. Clients queue the
// envelopes that arrive while they wait for another kind (a State while
// waiting for a Frame, say), so no answer is lost or answered twice.
bool TakeQueued(std::deque<proto::Envelope>& pending, proto::Envelope::KindCase kind, proto::Envelope& out);

}  // namespace sim4cv::detail
