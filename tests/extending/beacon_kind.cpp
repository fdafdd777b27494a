// An entity kind in one file: a beacon, a 0.5 x 0.5 x 2 m orange post that
// stands where it is spawned and turns on the spot at half a radian a
// second. Kinematic (no Bullet body), drawn as a box of its colour, labelled
// as an obstacle. Registered by one line, sim::RegisterEntityKind(demo::kBeacon);
// the worked example of docs/architecture.md, "Extending sim4cv".
#include <Eigen/Geometry>
#include <stdexcept>
#include <string>

#include "server/sim/entity_kind_registry.h"
#include "sim4cv.pb.h"

namespace sim4cv::demo {
namespace {

constexpr double kTurnRate = 0.5;  // rad/s
constexpr double kHalfHeight = 1.0;

Eigen::Quaterniond Heading(double yaw) { return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())); }

class Beacon final : public sim::KindBehaviour {
 public:
  void Spawn(const Eigen::Vector3d& position, double yaw, sim::Entity& entity) const override {
    if (position.z() != 0.0) {
      throw std::invalid_argument("a beacon stands on the ground: Spawn.position.z must be 0, not " +
                                  std::to_string(position.z()));
    }
    entity.body.position = {position.x(), position.y(), kHalfHeight};  // its box stands on the ground
    entity.body.orientation = Heading(yaw);
    entity.body.angular_velocity = {0.0, 0.0, kTurnRate};
  }
  void Step(sim::Entity& entity, const sim::State&, double dt) const override {
    entity.body.orientation = Heading(entity.body.Yaw() + kTurnRate * dt);
  }
};
const Beacon kBehaviour;

}  // namespace

extern const sim::EntityKindEntry kBeacon{{static_cast<sim::EntityKind>(9), "beacon", proto::OBJECT_CLASS_OBSTACLE},
                                          proto::OBJECT_CLASS_OBSTACLE,
                                          {0.25, 0.25, kHalfHeight},
                                          {0.95f, 0.45f, 0.05f},
                                          &kBehaviour};

}  // namespace sim4cv::demo
