#include "server/sim/track_servo.h"

#include <algorithm>
#include <cmath>

namespace sim4cv::sim {

const TrackerReport* NewestReportFor(const State& state, uint32_t entity_id) {
  const TrackerReport* newest = nullptr;
  for (const TrackerReport& report : state.tracker_reports) {
    if (report.entity_id != entity_id || report.image_width == 0) continue;
    if (!newest || report.frame_id > newest->frame_id) newest = &report;
  }
  return newest;
}

vehicles::QuadcopterCommand TrackCommand(UavOrder& order, uint32_t uav_id, const BodyState& uav, const State& state,
                                         double dt) {
  const TrackServoGains& g = kTrackServo;
  UavOrder::Track& servo = order.track;
  const double climb = g.altitude_p * (servo.altitude - uav.position.z());
  const TrackerReport* box = NewestReportFor(state, uav_id);
  if (!box || state.sim_time - box->received_at > g.report_timeout) {
    return vehicles::QuadcopterCommand::Velocity({0.0, 0.0, climb}, 0.0);  // nothing to go by: stay
  }
  if (servo.reference_height <= 0) servo.reference_height = box->height;
  const double half_width = 0.5 * box->image_width;
  const double half_height = 0.5 * box->image_height;
  // Offsets in [-1, 1] from the image centre: right and down positive.
  const double right = (box->x + 0.5 * box->width - half_width) / half_width;
  const double down = (box->y + 0.5 * box->height - half_height) / half_height;
  // Positive when the target is farther than wanted: high in the image, small.
  const double far = -g.offset_weight * down + g.height_weight * (servo.reference_height - box->height) /
                                                   servo.reference_height;
  const auto integrate = [&](double& integral, double error) {
    integral = std::clamp(integral + error * dt, -g.max_integral, g.max_integral);
  };
  integrate(servo.yaw_integral, -right);
  integrate(servo.forward_integral, far);
  const double yaw_rate =
      std::clamp(g.yaw_p * -right + g.yaw_i * servo.yaw_integral, -g.max_yaw_rate, g.max_yaw_rate);
  const double forward = std::clamp(g.forward_p * far + g.forward_i * servo.forward_integral, -g.max_speed, g.max_speed);
  const double yaw = uav.Yaw();
  return vehicles::QuadcopterCommand::Velocity({std::cos(yaw) * forward, std::sin(yaw) * forward, climb}, yaw_rate);
}

}  // namespace sim4cv::sim
