// Helpers the traffic library's files share (the plan's layout, the step's
// random draws). Internal to the library.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

#include "server/sim/map/map.h"
#include "server/sim/map/prng.h"
#include "server/sim/traffic/footprint.h"
#include "server/sim/traffic/traffic_config.h"

namespace sim4cv::traffic::layout {

// Independent streams of one seed, so adding draws to one part of the plan
// does not shift another's.
inline constexpr uint64_t kJunctionStream = 0x7A3F'1C0D'5E11'6B01ull;
inline constexpr uint64_t kParkedStream = 0x51D2'88A4'03C7'9E02ull;
inline constexpr uint64_t kCarStream = 0xC4B0'6F3A'D915'2703ull;
inline constexpr uint64_t kWalkerStream = 0x2E97'D5B8'41AC'0F04ull;

inline map::Prng Stream(uint64_t seed, uint64_t salt) {
  uint64_t state = seed ^ salt;
  return map::Prng(map::SplitMix64(state));
}

// From a crosswalk's first walking line to its last: a car stopping for a
// walker stops before the whole crosswalk.
inline constexpr double kCrosswalkDepth = (kWalkLines - 1) * kWalkLineSpacing;
// Bumper to walker's body, the least a car keeps (its hard limit).
inline constexpr double kCarWalkerGap = 1.0;

// To the right of direction d, seen from above.
inline Eigen::Vector2d RightOf(const Eigen::Vector2d& d) { return {d.y(), -d.x()}; }
inline double HeadingOf(const Eigen::Vector2d& d) { return std::atan2(d.y(), d.x()); }

// Whether a disc keeps `clearance` off every object's footprint (trees count
// with their trunk: crowns are overhead).
inline bool ClearOfObjects(const map::Map& map, const Eigen::Vector2d& p, double clearance) {
  return std::all_of(map.objects.begin(), map.objects.end(),
                     [&](const map::MapObject& object) { return DistanceTo(FootprintOf(object), p) >= clearance; });
}
inline bool ClearOfObjects(const map::Map& map, const Box2& box, double clearance) {
  const Box2 grown = Grown(box, clearance);
  return std::none_of(map.objects.begin(), map.objects.end(),
                      [&](const map::MapObject& object) { return Overlap(grown, FootprintOf(object)); });
}

// The next draw in [0, 1) of a car's or walker's own splitmix64 stream.
inline double NextUniform(uint64_t& state) { return static_cast<double>(map::SplitMix64(state) >> 11) * 0x1.0p-53; }

// `wanted` of the indices 0..available-1, picked by `rng`, in increasing order.
inline std::vector<int> Choose(int available, int wanted, map::Prng& rng) {
  std::vector<int> order(static_cast<std::size_t>(available));
  for (int i = 0; i < available; ++i) order[i] = i;
  for (int i = available - 1; i > 0; --i) std::swap(order[i], order[rng.UniformInt(0, i)]);  // Fisher-Yates
  order.resize(static_cast<std::size_t>(std::min(wanted, available)));
  std::sort(order.begin(), order.end());
  return order;
}

}  // namespace sim4cv::traffic::layout
