#include "server/sim/log/replay_check.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "server/common/limits.h"

namespace sim4cv::runlog {
namespace {

using limits::kLogQuaternionNormTolerance;
using limits::kMaxWorldCoordinate;

// Where a value was read, for the message: "record 12 (frame 13), entity 1".
class Place {
 public:
  Place(const ReplayTrack& track, std::size_t index) : track_(track), index_(index) {}
  void SetEntity(uint32_t id) { entity_ = id; }

  [[noreturn]] void Refuse(const std::string& field, double value, const std::string& rule) const {
    std::ostringstream message;
    message << "record " << index_ << " (frame " << track_.frame_id(index_) << ")";
    if (entity_) message << ", entity " << *entity_;
    message << ": " << field << " = " << value << " " << rule;
    throw std::invalid_argument(message.str());
  }

  // A coordinate as a client's would be checked: finite and within +-kMaxWorldCoordinate.
  void Coordinate(const std::string& field, double value) const {
    if (!std::isfinite(value)) Refuse(field, value, "is not finite");
    if (std::abs(value) > kMaxWorldCoordinate) {
      std::ostringstream rule;
      rule << "is outside +-" << kMaxWorldCoordinate << " (limits::kMaxWorldCoordinate)";
      Refuse(field, value, rule.str());
    }
  }

  void Vector(const char* name, const Eigen::Vector3d& v) const {
    static const char* const kAxes[] = {".x", ".y", ".z"};
    for (int i = 0; i < 3; ++i) Coordinate(name + std::string(kAxes[i]), v[i]);
  }

 private:
  const ReplayTrack& track_;
  std::size_t index_;
  std::optional<uint32_t> entity_;
};

void CheckOrientation(const Place& place, const Eigen::Quaterniond& q) {
  const double parts[] = {q.w(), q.x(), q.y(), q.z()};
  static const char* const kNames[] = {"orientation.w", "orientation.x", "orientation.y", "orientation.z"};
  for (int i = 0; i < 4; ++i) {
    if (!std::isfinite(parts[i])) place.Refuse(kNames[i], parts[i], "is not finite");
  }
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > kLogQuaternionNormTolerance) {
    std::ostringstream rule;
    rule << "(a rotation's quaternion has norm 1, within " << kLogQuaternionNormTolerance
         << ": limits::kLogQuaternionNormTolerance)";
    place.Refuse("|orientation|", norm, rule.str());
  }
}

}  // namespace

void CheckReplayValues(const ReplayTrack& track) {
  for (std::size_t index = 0; index < track.frame_count(); ++index) {
    Place place(track, index);
    const double time = track.sim_time(index);
    if (!std::isfinite(time) || time < 0) place.Refuse("sim_time", time, "is not a finite time >= 0");
    for (const EntityLog& entity : track.EntitiesAt(index)) {
      place.SetEntity(entity.id);
      place.Vector("position", entity.body.position);
      CheckOrientation(place, entity.body.orientation);
      place.Vector("linear_velocity", entity.body.linear_velocity);
      place.Vector("angular_velocity", entity.body.angular_velocity);
    }
  }
}

}  // namespace sim4cv::runlog
