#include "requests.h"

#include <algorithm>

#include "protocol/framing.h"

namespace sim4cv::detail {

proto::Envelope HelloRequest(const std::string& client_name, uint32_t protocol_version) {
  proto::Envelope envelope;
  envelope.mutable_hello()->set_protocol_version(protocol_version == 0 ? wire::kProtocolVersion : protocol_version);
  envelope.mutable_hello()->set_client_name(client_name);
  return envelope;
}

proto::Envelope SubscribeRequest(const std::string& camera, const std::vector<proto::Channel>& channels,
                                 proto::Delivery delivery, bool with_state) {
  proto::Envelope envelope;
  proto::Subscribe& subscribe = *envelope.mutable_subscribe();
  subscribe.set_camera(camera);
  for (const proto::Channel channel : channels) subscribe.add_channels(channel);
  subscribe.set_delivery(delivery);
  subscribe.set_with_state(with_state);
  return envelope;
}

proto::Envelope StepRequest() {
  proto::Envelope envelope;
  envelope.mutable_step();
  return envelope;
}

proto::Envelope TrackerOutputRequest(uint64_t frame_id, float x, float y, float width, float height, float confidence) {
  proto::Envelope envelope;
  proto::TrackerOutput& output = *envelope.mutable_tracker_output();
  output.set_frame_id(frame_id);
  output.mutable_box()->set_x(x);
  output.mutable_box()->set_y(y);
  output.mutable_box()->set_width(width);
  output.mutable_box()->set_height(height);
  output.set_confidence(confidence);
  return envelope;
}

proto::Envelope ControlsRequest(uint32_t entity_id, float steering, float throttle, float brake) {
  proto::Envelope envelope;
  proto::Controls& controls = *envelope.mutable_controls();
  controls.set_entity_id(entity_id);
  controls.set_steering(steering);
  controls.set_throttle(throttle);
  controls.set_brake(brake);
  return envelope;
}

bool TakeQueued(std::deque<proto::Envelope>& pending, proto::Envelope::KindCase kind, proto::Envelope& out) {
  const auto queued =
      std::find_if(pending.begin(), pending.end(), [kind](const proto::Envelope& e) { return e.kind_case() == kind; });
  if (queued == pending.end()) return false;
  out.Swap(&*queued);
  pending.erase(queued);
  return true;
}

}  // namespace sim4cv::detail
