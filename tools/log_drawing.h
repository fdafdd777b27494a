// Draws a map from above with the trajectories of logged runs over it, like
// the paper's figure of four UAVs "controlled by different trackers indicated
// by the different colors" and its "path of each tracker ... drawn on the 2D
// world map". Used by sim4cv_logdraw; the palette is here so tests can find
// each trajectory's pixels in the PNG.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "server/sim/map/map.h"

namespace sim4cv::tools {

// Trajectory colours (BGR), in the order tracks are given; they repeat after
// the last. Saturated hues that no map element uses, so tracks stand out
// from the sand, grass, asphalt and dressing.
inline constexpr std::array<std::array<uint8_t, 3>, 8> kTrackColours = {{
    {{30, 30, 220}},  // red
    {{220, 100, 0}},  // blue
    {{200, 0, 200}},  // magenta
    {{0, 140, 255}},  // orange
    {{180, 180, 0}},  // teal
    {{130, 0, 90}},   // purple
    {{0, 0, 120}},    // dark red
    {{255, 0, 110}},  // violet blue
}};
cv::Scalar TrackColour(std::size_t index);

struct Track {
  std::string legend;                   // e.g. "mosse.s4log (MOSSE_CA): uav"
  std::vector<Eigen::Vector2d> points;  // world x, y in metres, in time order
};

// `px_per_m` <= 0 picks a scale that makes the longer side about 1000 px.
// The view covers the map and every track point. Below the map is a legend
// of the tracks with their colours, a scale bar and the map's name.
cv::Mat DrawRunMap(const map::Map& map, const std::vector<Track>& tracks, double px_per_m);

}  // namespace sim4cv::tools
