#include "server/sim/traffic_bodies.h"

namespace sim4cv::sim {
namespace {

BodyState GroundBody(const Eigen::Vector3d& position, double heading, const Eigen::Vector3d& velocity,
                     double yaw_rate) {
  BodyState body;
  body.position = position;
  body.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()));
  body.linear_velocity = velocity;
  body.angular_velocity = {0.0, 0.0, yaw_rate};
  return body;
}

}  // namespace

BodyState BodyOf(const traffic::MovingCar& car) {
  return GroundBody(car.position, car.heading, car.linear_velocity, car.yaw_rate);
}

BodyState BodyOf(const traffic::Walker& walker) {
  return GroundBody(walker.position, walker.heading, walker.linear_velocity, 0.0);
}

void PlaceAt(const BodyState& body, traffic::MovingCar& car) {
  car.position = body.position;
  car.heading = body.Yaw();
  car.linear_velocity = body.linear_velocity;
  car.yaw_rate = body.angular_velocity.z();
}

void PlaceAt(const BodyState& body, traffic::Walker& walker) {
  walker.position = body.position;
  walker.heading = body.Yaw();
  walker.linear_velocity = body.linear_velocity;
}

}  // namespace sim4cv::sim
