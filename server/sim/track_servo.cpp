#include "server/sim/track_servo.h"

#include <algorithm>
#include <cmath>

#include "server/sim/controllers.h"

namespace sim4cv::sim {

const TrackerReport* NewestReportFor(const State& state, uint32_t entity_id) {
  const TrackerReport* newest = nullptr;
  for (const TrackerReport& report : state.tracker_reports) {
    if (report.entity_id != entity_id || report.image_width == 0) continue;
    if (!newest || report.frame_id > newest->frame_id) newest = &report;
  }
  return newest;
}

std::optional<Eigen::Vector2d> GroundOffset(const UavOrder::Track& camera, const TrackerReport& box, double height) {
  const double focal = 0.5 * box.image_height / std::tan(0.5 * camera.fov_y);
  const double right = (box.x + 0.5 * box.width - 0.5 * box.image_width) / focal;
  const double down = (box.y + 0.5 * box.height - 0.5 * box.image_height) / focal;
  const double c = std::cos(camera.pitch_down), s = std::sin(camera.pitch_down);
  // The ray forward + right * R + down * D with the camera's axes in the
  // heading frame: forward (c, 0, -s), right (0, -1, 0), down (-s, 0, -c).
  const Eigen::Vector3d ray(c - down * s, -right, -s - down * c);
  if (ray.z() > -1e-3 || height <= 0) return std::nullopt;
  return Eigen::Vector2d(ray.x(), ray.y()) * (height / -ray.z());
}

vehicles::QuadcopterCommand TrackCommand(UavOrder& order, uint32_t uav_id, const BodyState& uav, const State& state) {
  const TrackServoGains& g = kTrackServo;
  UavOrder::Track& servo = order.track;
  const double yaw = uav.Yaw();
  const TrackerReport* box = NewestReportFor(state, uav_id);
  if (box && box->frame_id != servo.frame) {
    if (const auto offset = GroundOffset(servo, *box, uav.position.z() - g.target_height)) {
      const Eigen::Rotation2Dd heading(yaw);
      const Eigen::Vector2d target = uav.position.head<2>() + heading * *offset;
      if (servo.frame != 0 && box->received_at > servo.time) {
        const Eigen::Vector2d seen = (target - servo.target) / (box->received_at - servo.time);
        servo.velocity += g.velocity_smoothing * (seen - servo.velocity);
      }
      servo.target = target;
      servo.time = box->received_at;
    }
    servo.frame = box->frame_id;
  }
  if (servo.frame == 0 || !box || state.sim_time - box->received_at > g.report_timeout) {
    return vehicles::QuadcopterCommand::Hold({uav.position.x(), uav.position.y(), servo.altitude},
                                             yaw);  // nothing to go by: stay
  }
  // The target now, by its estimated velocity since the box came.
  const Eigen::Vector2d target = servo.target + servo.velocity * (state.sim_time - servo.time);
  const Eigen::Vector2d to_target = target - uav.position.head<2>();
  const double facing = std::atan2(to_target.y(), to_target.x());
  const double behind =
      servo.distance > 0 ? servo.distance : (servo.altitude - g.target_height) / std::tan(servo.pitch_down);
  const Eigen::Vector2d station = target - Eigen::Vector2d(std::cos(facing), std::sin(facing)) * behind;
  // The position hold flies to the station with the target's velocity fed forward.
  return vehicles::QuadcopterCommand::Hold({station.x(), station.y(), servo.altitude}, facing,
                                           {servo.velocity.x(), servo.velocity.y(), 0.0});
}

}  // namespace sim4cv::sim
