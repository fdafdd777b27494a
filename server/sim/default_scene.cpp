#include "server/sim/scene.h"

namespace sim4cv::sim {

const std::string& DefaultSceneText() {
  static const std::string text = R"SCENE(
# sim4cv scene: the embedded default scene (see docs/scenes.md)
scene default
ground 150
lane_width 4
car_speed 6
uav_altitude 15
camera_pitch 60
# road centre line, a closed loop driven counter-clockwise (x east, y north, metres)
road -40.00 -40.00
road -30.00 -40.00
road -20.00 -40.00
road -10.00 -40.00
road 0.00 -40.00
road 10.00 -40.00
road 20.00 -40.00
road 30.00 -40.00
road 40.00 -40.00
road 45.18 -39.32
road 50.00 -37.32
road 54.14 -34.14
road 57.32 -30.00
road 59.32 -25.18
road 60.00 -20.00
road 60.00 -10.00
road 60.00 0.00
road 60.00 10.00
road 60.00 20.00
road 59.32 25.18
road 57.32 30.00
road 54.14 34.14
road 50.00 37.32
road 45.18 39.32
road 40.00 40.00
road 30.00 40.00
road 20.00 40.00
road 10.00 40.00
road 0.00 40.00
road -10.00 40.00
road -20.00 40.00
road -30.00 40.00
road -40.00 40.00
road -45.18 39.32
road -50.00 37.32
road -54.14 34.14
road -57.32 30.00
road -59.32 25.18
road -60.00 20.00
road -60.00 10.00
road -60.00 0.00
road -60.00 -10.00
road -60.00 -20.00
road -59.32 -25.18
road -57.32 -30.00
road -54.14 -34.14
road -50.00 -37.32
road -45.18 -39.32
# building centre_x centre_y half_x half_y height yaw_deg
building -30 0 8 10 12 0
building 0 0 10 8 18 0
building 30 0 8 10 9 0
building -20 -62 8 6 14 0
building 20 -62 10 6 10 0
building 75 -20 6 10 16 0
building 75 20 6 8 8 15
building 20 62 10 6 20 0
building -20 62 8 6 11 0
building -75 15 6 10 13 0
building -75 -25 6 8 9 -10
building 55 -60 5 5 7 30
)SCENE";
  return text;
}

}  // namespace sim4cv::sim
