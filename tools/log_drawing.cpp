#include "tools/log_drawing.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "server/sim/map/road_graph.h"

namespace sim4cv::tools {
namespace {

using map::Map;

constexpr int kMarginPx = 24;
constexpr int kShift = 4;  // sub-pixel bits: OpenCV draws at 1/16 px, so thin curves stay smooth
constexpr double kSubPixel = 1 << kShift;
constexpr double kTargetSidePx = 1000.0;  // the longer side at the automatic scale
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kFontScale = 0.5;
constexpr int kLegendRowPx = 22;

// Map colours (BGR): muted, so the saturated track colours stand out.
const cv::Scalar kSand(150, 196, 222), kGrass(110, 165, 120);
const cv::Scalar kCurb(70, 70, 70), kAsphalt(110, 110, 110), kMarking(235, 235, 235);
const cv::Scalar kHouse(120, 130, 150), kHouseEdge(60, 65, 80);
const cv::Scalar kCrown(50, 115, 50), kCrownEdge(30, 80, 30);
const cv::Scalar kLantern(0, 215, 255), kPark(140, 210, 150), kObstacle(40, 80, 130);
const cv::Scalar kBlack(0, 0, 0), kWhite(255, 255, 255);

// World metres to image pixels: north up, the view's north-west corner at
// the margin. Points come back in OpenCV's fixed point (kShift bits).
class View {
 public:
  View(const Eigen::AlignedBox2d& world, double px_per_m) : world_(world), scale_(px_per_m) {}
  cv::Point Px(const Eigen::Vector2d& p) const {
    return {static_cast<int>(std::lround((kMarginPx + (p.x() - world_.min().x()) * scale_) * kSubPixel)),
            static_cast<int>(std::lround((kMarginPx + (world_.max().y() - p.y()) * scale_) * kSubPixel))};
  }
  int Length(double metres) const { return std::max(1, static_cast<int>(std::lround(metres * scale_))); }
  int width() const { return 2 * kMarginPx + static_cast<int>(std::ceil(world_.sizes().x() * scale_)); }
  int height() const { return 2 * kMarginPx + static_cast<int>(std::ceil(world_.sizes().y() * scale_)); }
  double scale() const { return scale_; }

 private:
  Eigen::AlignedBox2d world_;
  double scale_;
};

std::vector<cv::Point> ToPixels(const View& view, const std::vector<Eigen::Vector2d>& points) {
  std::vector<cv::Point> pixels;
  pixels.reserve(points.size());
  for (const Eigen::Vector2d& p : points) pixels.push_back(view.Px(p));
  return pixels;
}

// A lane's centre line moved `left` metres to the left of its direction of
// travel, sampled every `step` metres or closer.
std::vector<Eigen::Vector2d> SampleLane(const map::LaneCurve& curve, double left, double step) {
  const int pieces = std::max(1, static_cast<int>(std::ceil(curve.length() / step)));
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i <= pieces; ++i) {
    const double s = curve.length() * i / pieces;
    const double heading = curve.HeadingAt(s);
    points.push_back(curve.PointAt(s) + left * Eigen::Vector2d(-std::sin(heading), std::cos(heading)));
  }
  return points;
}

void DrawPolyline(cv::Mat& image, const View& view, const std::vector<Eigen::Vector2d>& points,
                  const cv::Scalar& colour, int thickness) {
  const std::vector<cv::Point> pixels = ToPixels(view, points);
  cv::polylines(image, pixels, false, colour, thickness, cv::LINE_AA, kShift);
}

// Every other `dash` metres of a polyline.
void DrawDashed(cv::Mat& image, const View& view, const std::vector<Eigen::Vector2d>& points, double dash,
                const cv::Scalar& colour) {
  double travelled = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) {
    const double length = (points[i] - points[i - 1]).norm();
    if (std::fmod(travelled + length / 2, 2 * dash) < dash) {
      cv::line(image, view.Px(points[i - 1]), view.Px(points[i]), colour, 1, cv::LINE_AA, kShift);
    }
    travelled += length;
  }
}

// Road surface as the union of every lane's strip: first a wider dark band
// for all lanes, then the asphalt over it, so only the outer edge of the
// union shows as a curb, junctions included. Then the dashed centre line
// between the two lanes, except inside junctions.
void DrawRoads(cv::Mat& image, const View& view, const Map& map) {
  const map::RoadGraph graph(map);
  const double step = std::max(0.25, 2.0 / view.scale());  // about 2 px
  std::vector<std::vector<Eigen::Vector2d>> lanes;
  for (const map::LaneSegment& segment : graph.segments()) lanes.push_back(SampleLane(segment.curve, 0.0, step));
  const int asphalt = view.Length(map::kLaneWidth);
  for (const auto& lane : lanes) DrawPolyline(image, view, lane, kCurb, asphalt + 2);
  for (const auto& lane : lanes) DrawPolyline(image, view, lane, kAsphalt, asphalt);
  for (const map::LaneSegment& segment : graph.segments()) {
    const map::TileKind kind = map.KindAt(segment.tile);
    if (kind == map::TileKind::kTJunction || kind == map::TileKind::kCrossroads) continue;
    DrawDashed(image, view, SampleLane(segment.curve, map::kLaneWidth / 2, step), 3.0, kMarking);
  }
}

// The footprint of an object as a turned rectangle.
std::vector<cv::Point> Footprint(const View& view, const map::MapObject& object) {
  const map::ObjectShape& shape = map::ShapeOf(object.kind);
  const Eigen::Rotation2Dd turn(object.rotation_deg * M_PI / 180.0);
  std::vector<cv::Point> corners;
  for (const auto& [sx, sy] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
    corners.push_back(view.Px(object.position + turn * Eigen::Vector2d(sx * shape.half_x, sy * shape.half_y)));
  }
  return corners;
}

void DrawObject(cv::Mat& image, const View& view, const map::MapObject& object) {
  const cv::Point centre = view.Px(object.position);
  switch (object.kind) {
    case map::ObjectKind::kPark:
      cv::fillConvexPoly(image, Footprint(view, object), kPark, cv::LINE_AA, kShift);
      break;
    case map::ObjectKind::kHouse: {
      const std::vector<cv::Point> corners = Footprint(view, object);
      cv::fillConvexPoly(image, corners, kHouse, cv::LINE_AA, kShift);
      cv::polylines(image, corners, true, kHouseEdge, 1, cv::LINE_AA, kShift);
      break;
    }
    case map::ObjectKind::kObstacle:
      cv::fillConvexPoly(image, Footprint(view, object), kObstacle, cv::LINE_AA, kShift);
      break;
    case map::ObjectKind::kTree: {
      const int radius = view.Length(map::ShapeOf(object.kind).crown_radius) << kShift;
      cv::circle(image, centre, radius, kCrown, cv::FILLED, cv::LINE_AA, kShift);
      cv::circle(image, centre, radius, kCrownEdge, 1, cv::LINE_AA, kShift);
      break;
    }
    case map::ObjectKind::kLantern:
      cv::circle(image, centre, 3 << kShift, kLantern, cv::FILLED, cv::LINE_AA, kShift);
      cv::circle(image, centre, 3 << kShift, kBlack, 1, cv::LINE_AA, kShift);
      break;
  }
}

// Flat things first (parks, obstacles on the road), then houses, then the
// tree crowns that may overhang them, then lanterns on top.
void DrawObjects(cv::Mat& image, const View& view, const Map& map) {
  for (map::ObjectKind kind : {map::ObjectKind::kPark, map::ObjectKind::kObstacle, map::ObjectKind::kHouse,
                               map::ObjectKind::kTree, map::ObjectKind::kLantern}) {
    for (const map::MapObject& object : map.objects) {
      if (object.kind == kind) DrawObject(image, view, object);
    }
  }
}

// The start as a dot and the end (where a failing tracker lost the car) as a
// cross, both edged in black so they read on any background.
void DrawStart(cv::Mat& image, cv::Point at, const cv::Scalar& colour) {
  cv::circle(image, at, 6 << kShift, kBlack, cv::FILLED, cv::LINE_AA, kShift);
  cv::circle(image, at, 5 << kShift, colour, cv::FILLED, cv::LINE_AA, kShift);
}
void DrawEnd(cv::Mat& image, cv::Point at, const cv::Scalar& colour) {
  const int arm = 6 << kShift;
  for (const auto& [thickness, c] : {std::pair{5, kBlack}, {3, colour}}) {
    cv::line(image, at + cv::Point(-arm, -arm), at + cv::Point(arm, arm), c, thickness, cv::LINE_AA, kShift);
    cv::line(image, at + cv::Point(-arm, arm), at + cv::Point(arm, -arm), c, thickness, cv::LINE_AA, kShift);
  }
}

void DrawTrack(cv::Mat& image, const View& view, const Track& track, const cv::Scalar& colour) {
  if (track.points.empty()) return;
  DrawPolyline(image, view, track.points, colour, 3);
  DrawStart(image, view.Px(track.points.front()), colour);
  DrawEnd(image, view.Px(track.points.back()), colour);
}

int TextWidth(const std::string& text) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, kFontScale, 1, &baseline).width;
}

void PutText(cv::Mat& image, const std::string& text, cv::Point at) {
  cv::putText(image, text, at, kFont, kFontScale, kBlack, 1, cv::LINE_AA);
}

std::string MapCaption(const Map& map) {
  char text[160];
  std::snprintf(text, sizeof text, "map %s: %dx%d tiles of %g m    o start   x end", map.name.c_str(), map.width,
                map.height, map.tile_size);
  return text;
}

// A bar of a round length near 100 px, labelled in metres.
void DrawScaleBar(cv::Mat& image, const View& view, cv::Point right_end) {
  double metres = 1;
  for (double candidate : {1, 2, 5, 10, 20, 50, 100, 200, 500, 1000}) {
    if (candidate * view.scale() <= 120) metres = candidate;
  }
  const int length = view.Length(metres);
  const cv::Point left_end = right_end - cv::Point(length, 0);
  cv::line(image, left_end, right_end, kBlack, 2);
  for (const cv::Point& end : {left_end, right_end}) cv::line(image, end - cv::Point(0, 5), end, kBlack, 2);
  const std::string label = std::to_string(static_cast<int>(metres)) + " m";
  PutText(image, label, left_end - cv::Point(TextWidth(label) + 8, -4));
}

// Below the map: the caption and scale bar, then one row per track.
void DrawLegend(cv::Mat& image, const View& view, const Map& map, const std::vector<Track>& tracks) {
  int y = view.height() + 4;
  PutText(image, MapCaption(map), {kMarginPx, y});
  DrawScaleBar(image, view, {image.cols - kMarginPx, y - 4});
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    y += kLegendRowPx;
    const cv::Scalar colour = TrackColour(i);
    cv::line(image, {kMarginPx, y - 5}, {kMarginPx + 36, y - 5}, colour, 3, cv::LINE_AA);
    PutText(image, tracks[i].legend, {kMarginPx + 46, y});
  }
}

Eigen::AlignedBox2d ViewBounds(const Map& map, const std::vector<Track>& tracks) {
  Eigen::AlignedBox2d bounds(-map.HalfExtent(), map.HalfExtent());
  for (const Track& track : tracks) {
    for (const Eigen::Vector2d& p : track.points) bounds.extend(p);
  }
  return bounds;
}

}  // namespace

cv::Scalar TrackColour(std::size_t index) {
  const auto& c = kTrackColours[index % kTrackColours.size()];
  return {static_cast<double>(c[0]), static_cast<double>(c[1]), static_cast<double>(c[2])};
}

cv::Mat DrawRunMap(const Map& map, const std::vector<Track>& tracks, double px_per_m) {
  const Eigen::AlignedBox2d bounds = ViewBounds(map, tracks);
  if (px_per_m <= 0) px_per_m = std::clamp(kTargetSidePx / bounds.sizes().maxCoeff(), 0.5, 20.0);
  const View view(bounds, px_per_m);

  int width = std::max(view.width(), TextWidth(MapCaption(map)) + 2 * kMarginPx + 200);
  for (const Track& track : tracks) width = std::max(width, TextWidth(track.legend) + 2 * kMarginPx + 46);
  const int height = view.height() + 16 + kLegendRowPx * static_cast<int>(tracks.size());
  cv::Mat image(height, width, CV_8UC3, kWhite);

  const cv::Rect ground(kMarginPx, kMarginPx, view.width() - 2 * kMarginPx, view.height() - 2 * kMarginPx);
  image(ground).setTo(map.surroundings == map::Surroundings::kUrban ? kGrass : kSand);
  DrawRoads(image, view, map);
  DrawObjects(image, view, map);
  for (std::size_t i = 0; i < tracks.size(); ++i) DrawTrack(image, view, tracks[i], TrackColour(i));
  cv::rectangle(image, ground, kBlack, 1);
  DrawLegend(image, view, map, tracks);
  return image;
}

}  // namespace sim4cv::tools
