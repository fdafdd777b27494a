// The client requests every transport's client sends, built in one place so
// the TCP, UDP and shared-memory clients cannot drift apart.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "sim4cv.pb.h"

namespace sim4cv {
struct CameraSetup;  // sim4cv/client.h
}

namespace sim4cv::detail {

// protocol_version 0 means this build's version.
// `token`: Hello.token, the daemon's access token (AccessToken).
proto::Envelope HelloRequest(const std::string& client_name, uint32_t protocol_version, const std::string& token = {});
// The access token for the daemon's `kind` ("tcp", "udp") endpoint at
// host:port: SIM4CV_TOKEN, or for a local host the daemon's token file for
// it (docs/security.md); empty if neither.
std::string AccessToken(const std::string& kind, const std::string& host, uint16_t port);
proto::Envelope SubscribeRequest(const std::string& camera, const std::vector<proto::Channel>& channels,
                                 proto::Delivery delivery, bool with_state);
proto::Envelope StepRequest();
proto::Envelope TrackerOutputRequest(uint64_t frame_id, float x, float y, float width, float height, float confidence);
proto::Envelope ControlsRequest(uint32_t entity_id, float steering, float throttle, float brake);

// Configure requests (docs/protocol.md, "Configuring the world"), without a
// request_id: the client that sends one assigns it.
proto::Configure LoadMapByNameRequest(const std::string& name, const std::string& route, float car_speed,
                                      const std::optional<proto::TrafficSettings>& traffic);
proto::Configure LoadMapTextRequest(const std::string& text, const std::string& route, float car_speed,
                                    const std::optional<proto::TrafficSettings>& traffic);
proto::Configure SpawnRequest(proto::EntityKind kind, const std::string& name, double x, double y, double z,
                              double yaw_deg, bool snap_to_lane);
proto::Configure RemoveRequest(uint32_t entity_id);
proto::Configure SetRouteRequest(uint32_t entity_id, const std::string& route_name, float speed);
proto::Configure SetWaypointsRequest(uint32_t entity_id, const std::vector<std::array<double, 2>>& points, bool closed,
                                     float speed);
proto::Configure SetSpeedRequest(uint32_t entity_id, float speed);
proto::Configure UavFollowRequest(uint32_t uav_id, uint32_t target_id, double altitude, double pitch_down_deg);
proto::Configure UavHoldRequest(uint32_t uav_id, double x, double y, double z, double yaw_deg);
proto::Configure UavVelocityRequest(uint32_t uav_id, double vx, double vy, double vz, double yaw_rate_deg);
proto::Configure UavTrackRequest(uint32_t uav_id, const std::string& camera, double distance, double altitude);
proto::Configure AddCameraRequest(const CameraSetup& camera);
proto::Configure RemoveCameraRequest(const std::string& name);
proto::Configure ResetRequest();
proto::Configure GetWorldRequest();
proto::Configure SetConditionsRequest(const std::string& preset, std::optional<double> hour,
                                      const std::string& quality);
proto::Configure QueryRoadRequest(double x, double y, uint32_t count, double step, std::optional<double> heading_deg);

// Moves the oldest queued envelope that `wanted` accepts into `out`. Clients
// queue the envelopes that arrive while they wait for another kind (a State
// while waiting for a Frame, say), so no answer is lost or answered twice.
template <typename Wanted>
bool TakeQueuedIf(std::deque<proto::Envelope>& pending, Wanted&& wanted, proto::Envelope& out) {
  for (auto queued = pending.begin(); queued != pending.end(); ++queued) {
    if (!wanted(static_cast<const proto::Envelope&>(*queued))) continue;
    out.Swap(&*queued);
    pending.erase(queued);
    return true;
  }
  return false;
}

// The oldest queued envelope of `kind`.
bool TakeQueued(std::deque<proto::Envelope>& pending, proto::Envelope::KindCase kind, proto::Envelope& out);

}  // namespace sim4cv::detail
