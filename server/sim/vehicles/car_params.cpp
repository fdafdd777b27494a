#include "server/sim/vehicles/car_params.h"

namespace sim4cv::vehicles {
namespace {

constexpr double kGravity = 9.81;

}  // namespace

double StaticSuspensionLength(const CarParams& p) {
  return p.suspension_rest_length - kGravity / (kWheelCount * p.suspension_stiffness);
}

double BoxCentreHeightAtRest(const CarParams& params) {
  // Wheel radius + static suspension length above the ground, plus the
  // depth of the suspension tops below the box centre.
  return params.wheel_radius + StaticSuspensionLength(params) - params.suspension_top_z;
}

}  // namespace sim4cv::vehicles
