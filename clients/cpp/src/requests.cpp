#include "requests.h"

#include "protocol/framing.h"
#include "sim4cv/client.h"  // CameraSetup

namespace sim4cv::detail {
namespace {

void SetVec3(proto::Vec3& out, double x, double y, double z) {
  out.set_x(x);
  out.set_y(y);
  out.set_z(z);
}

}  // namespace

proto::Envelope HelloRequest(const std::string& client_name, uint32_t protocol_version, const std::string& token) {
  proto::Envelope envelope;
  envelope.mutable_hello()->set_protocol_version(protocol_version == 0 ? wire::kProtocolVersion : protocol_version);
  envelope.mutable_hello()->set_client_name(client_name);
  envelope.mutable_hello()->set_token(token);
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

namespace {

proto::Configure LoadMapRequest(const std::string& route, float car_speed,
                                const std::optional<proto::TrafficSettings>& traffic) {
  proto::Configure request;
  request.mutable_load_map()->set_route(route);
  request.mutable_load_map()->set_car_speed(car_speed);
  if (traffic) *request.mutable_load_map()->mutable_traffic() = *traffic;
  return request;
}

}  // namespace

proto::Configure LoadMapByNameRequest(const std::string& name, const std::string& route, float car_speed,
                                      const std::optional<proto::TrafficSettings>& traffic) {
  proto::Configure request = LoadMapRequest(route, car_speed, traffic);
  request.mutable_load_map()->set_name(name);
  return request;
}

proto::Configure LoadMapTextRequest(const std::string& text, const std::string& route, float car_speed,
                                    const std::optional<proto::TrafficSettings>& traffic) {
  proto::Configure request = LoadMapRequest(route, car_speed, traffic);
  request.mutable_load_map()->set_text(text);
  return request;
}

proto::Configure SpawnRequest(proto::EntityKind kind, const std::string& name, double x, double y, double z,
                              double yaw_deg, bool snap_to_lane) {
  proto::Configure request;
  proto::Spawn& spawn = *request.mutable_spawn();
  spawn.set_kind(kind);
  spawn.set_name(name);
  SetVec3(*spawn.mutable_position(), x, y, z);
  spawn.set_yaw_deg(yaw_deg);
  spawn.set_snap_to_lane(snap_to_lane);
  return request;
}

proto::Configure RemoveRequest(uint32_t entity_id) {
  proto::Configure request;
  request.mutable_remove()->set_entity_id(entity_id);
  return request;
}

proto::Configure SetRouteRequest(uint32_t entity_id, const std::string& route_name, float speed) {
  proto::Configure request;
  proto::SetRoute& route = *request.mutable_set_route();
  route.set_entity_id(entity_id);
  route.set_route_name(route_name);
  route.set_speed(speed);
  return request;
}

proto::Configure SetWaypointsRequest(uint32_t entity_id, const std::vector<std::array<double, 2>>& points, bool closed,
                                     float speed) {
  proto::Configure request;
  proto::SetRoute& route = *request.mutable_set_route();
  route.set_entity_id(entity_id);
  proto::Waypoints& waypoints = *route.mutable_waypoints();
  for (const auto& [x, y] : points) {
    proto::Vec2& point = *waypoints.add_points();
    point.set_x(x);
    point.set_y(y);
  }
  waypoints.set_closed(closed);
  route.set_speed(speed);
  return request;
}

proto::Configure SetSpeedRequest(uint32_t entity_id, float speed) {
  proto::Configure request;
  proto::SetRoute& route = *request.mutable_set_route();
  route.set_entity_id(entity_id);
  route.set_keep_route(true);
  route.set_speed(speed);
  return request;
}

proto::Configure UavFollowRequest(uint32_t uav_id, uint32_t target_id, double altitude, double pitch_down_deg) {
  proto::Configure request;
  proto::CommandUav& command = *request.mutable_command_uav();
  command.set_entity_id(uav_id);
  command.mutable_follow()->set_target_id(target_id);
  command.mutable_follow()->set_altitude(altitude);
  command.mutable_follow()->set_pitch_down_deg(pitch_down_deg);
  return request;
}

proto::Configure UavHoldRequest(uint32_t uav_id, double x, double y, double z, double yaw_deg) {
  proto::Configure request;
  proto::CommandUav& command = *request.mutable_command_uav();
  command.set_entity_id(uav_id);
  SetVec3(*command.mutable_hold()->mutable_position(), x, y, z);
  command.mutable_hold()->set_yaw_deg(yaw_deg);
  return request;
}

proto::Configure UavVelocityRequest(uint32_t uav_id, double vx, double vy, double vz, double yaw_rate_deg) {
  proto::Configure request;
  proto::CommandUav& command = *request.mutable_command_uav();
  command.set_entity_id(uav_id);
  SetVec3(*command.mutable_velocity()->mutable_velocity(), vx, vy, vz);
  command.mutable_velocity()->set_yaw_rate_deg(yaw_rate_deg);
  return request;
}

proto::Configure UavTrackRequest(uint32_t uav_id, const std::string& camera, double distance, double altitude) {
  proto::Configure request;
  proto::CommandUav& command = *request.mutable_command_uav();
  command.set_entity_id(uav_id);
  command.mutable_track()->set_camera(camera);
  command.mutable_track()->set_distance(distance);
  command.mutable_track()->set_altitude(altitude);
  return request;
}

proto::Configure AddCameraRequest(const CameraSetup& camera) {
  proto::Configure request;
  proto::AddCamera& add = *request.mutable_add_camera();
  add.set_name(camera.name);
  add.set_mounted_on(camera.mounted_on);
  add.set_width(camera.width);
  add.set_height(camera.height);
  add.set_fov_y_deg(camera.fov_y_deg);
  add.set_pitch_down_deg(camera.pitch_down_deg);
  add.set_yaw_deg(camera.yaw_deg);
  add.set_gimbal(camera.gimbal);
  SetVec3(*add.mutable_offset(), camera.x, camera.y, camera.z);
  return request;
}

proto::Configure RemoveCameraRequest(const std::string& name) {
  proto::Configure request;
  request.mutable_remove_camera()->set_name(name);
  return request;
}

proto::Configure ResetRequest() {
  proto::Configure request;
  request.mutable_reset();
  return request;
}

proto::Configure SetConditionsRequest(const std::string& preset, std::optional<double> hour,
                                      const std::string& quality) {
  proto::Configure request;
  proto::SetConditions& conditions = *request.mutable_set_conditions();
  conditions.set_preset(preset);
  if (hour) conditions.set_hour(*hour);
  conditions.set_quality(quality);
  return request;
}

proto::Configure GetWorldRequest() {
  proto::Configure request;
  request.mutable_get_world();
  return request;
}

proto::Configure QueryRoadRequest(double x, double y, uint32_t count, double step, std::optional<double> heading_deg) {
  proto::Configure request;
  proto::QueryRoad& query = *request.mutable_query_road();
  SetVec3(*query.mutable_point(), x, y, 0.0);
  query.set_count(count);
  query.set_step(step);
  query.set_use_heading(heading_deg.has_value());
  query.set_heading_deg(heading_deg.value_or(0.0));
  return request;
}

bool TakeQueued(std::deque<proto::Envelope>& pending, proto::Envelope::KindCase kind, proto::Envelope& out) {
  return TakeQueuedIf(
      pending, [kind](const proto::Envelope& e) { return e.kind_case() == kind; }, out);
}

}  // namespace sim4cv::detail
