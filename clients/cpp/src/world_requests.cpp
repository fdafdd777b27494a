// sim4cv::Client's Configure wrappers: one request each (built in
// requests.cpp), answered with the world after the change.
#include "requests.h"
#include "sim4cv/client.h"

namespace sim4cv {

proto::WorldInfo Client::ConfigureWorld(proto::Configure request) {
  return std::move(*Configure(std::move(request)).mutable_world());
}

proto::WorldInfo Client::LoadMapByName(const std::string& name, const std::string& route, float car_speed,
                                       const std::optional<proto::TrafficSettings>& traffic) {
  return ConfigureWorld(detail::LoadMapByNameRequest(name, route, car_speed, traffic));
}

proto::WorldInfo Client::LoadMapText(const std::string& text, const std::string& route, float car_speed,
                                     const std::optional<proto::TrafficSettings>& traffic) {
  return ConfigureWorld(detail::LoadMapTextRequest(text, route, car_speed, traffic));
}

uint32_t Client::Spawn(proto::EntityKind kind, const std::string& name, double x, double y, double z, double yaw_deg,
                       bool snap_to_lane) {
  return Configure(detail::SpawnRequest(kind, name, x, y, z, yaw_deg, snap_to_lane)).entity_id();
}

proto::WorldInfo Client::Remove(uint32_t entity_id) { return ConfigureWorld(detail::RemoveRequest(entity_id)); }

proto::WorldInfo Client::SetRoute(uint32_t entity_id, const std::string& route_name, float speed) {
  return ConfigureWorld(detail::SetRouteRequest(entity_id, route_name, speed));
}

proto::WorldInfo Client::SetWaypoints(uint32_t entity_id, const std::vector<std::array<double, 2>>& points, bool closed,
                                      float speed) {
  return ConfigureWorld(detail::SetWaypointsRequest(entity_id, points, closed, speed));
}

proto::WorldInfo Client::SetSpeed(uint32_t entity_id, float speed) {
  return ConfigureWorld(detail::SetSpeedRequest(entity_id, speed));
}

proto::WorldInfo Client::UavFollow(uint32_t uav_id, uint32_t target_id, double altitude, double pitch_down_deg) {
  return ConfigureWorld(detail::UavFollowRequest(uav_id, target_id, altitude, pitch_down_deg));
}

proto::WorldInfo Client::UavHold(uint32_t uav_id, double x, double y, double z, double yaw_deg) {
  return ConfigureWorld(detail::UavHoldRequest(uav_id, x, y, z, yaw_deg));
}

proto::WorldInfo Client::UavVelocity(uint32_t uav_id, double vx, double vy, double vz, double yaw_rate_deg) {
  return ConfigureWorld(detail::UavVelocityRequest(uav_id, vx, vy, vz, yaw_rate_deg));
}

proto::WorldInfo Client::UavTrack(uint32_t uav_id, const std::string& camera, double distance, double altitude) {
  return ConfigureWorld(detail::UavTrackRequest(uav_id, camera, distance, altitude));
}

proto::WorldInfo Client::SetCameraPose(const std::string& camera, double x, double y, double z, double yaw_deg,
                                       double pitch_down_deg) {
  proto::Configure request;
  proto::SetCameraPose& pose = *request.mutable_set_camera_pose();
  pose.set_camera(camera);
  pose.mutable_position()->set_x(x);
  pose.mutable_position()->set_y(y);
  pose.mutable_position()->set_z(z);
  pose.set_yaw_deg(yaw_deg);
  pose.set_pitch_down_deg(pitch_down_deg);
  return ConfigureWorld(std::move(request));
}

proto::WorldInfo Client::AddCamera(const CameraSetup& camera) {
  return ConfigureWorld(detail::AddCameraRequest(camera));
}

proto::WorldInfo Client::RemoveCamera(const std::string& name) {
  return ConfigureWorld(detail::RemoveCameraRequest(name));
}

proto::WorldInfo Client::Reset() { return ConfigureWorld(detail::ResetRequest()); }

proto::WorldInfo Client::GetWorld() { return ConfigureWorld(detail::GetWorldRequest()); }

proto::WorldInfo Client::SetEffects(const proto::CameraEffects& effects) {
  proto::Configure request;
  *request.mutable_set_effects() = effects;
  return ConfigureWorld(std::move(request));
}

proto::WorldInfo Client::SetConditions(const std::string& preset, std::optional<double> hour,
                                       const std::string& quality) {
  return ConfigureWorld(detail::SetConditionsRequest(preset, hour, quality));
}

proto::RoadQueryResult Client::QueryRoad(double x, double y, uint32_t count, double step,
                                         std::optional<double> heading_deg) {
  return std::move(*Configure(detail::QueryRoadRequest(x, y, count, step, heading_deg)).mutable_road());
}

}  // namespace sim4cv
