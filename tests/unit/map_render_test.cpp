#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "server/render/camera_math.h"
#include "server/render/gl_context.h"
#include "server/render/map_meshes.h"
#include "server/render/object_meshes.h"
#include "server/render/renderer.h"
#include "server/sim/map/map_text.h"
#include "sim4cv.pb.h"
#include "tests/support/rendered_frame.h"

namespace sim4cv::render {
namespace {

namespace fs = std::filesystem;

// The shipped maps, found from this file's path (tests/unit/ -> scenes/).
const fs::path kScenes = fs::path(__FILE__).parent_path().parent_path().parent_path() / "scenes";
constexpr InstanceId kFirstInstance = 10;  // past the car and UAV ids, as the daemon would place them
constexpr size_t kTriangleBudget = 30000;

std::vector<fs::path> ShippedMaps() {
  std::vector<fs::path> paths;
  for (const auto& entry : fs::recursive_directory_iterator(kScenes)) {
    if (entry.path().extension() == ".map") paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

struct BuiltMap {
  map::Map map;
  std::vector<MapDrawable> drawables;
};

BuiltMap Build(map::Map map) {
  BuiltMap built{std::move(map), {}};
  built.drawables = BuildMapDrawables(built.map, map::RoadGraph(built.map), kFirstInstance);
  return built;
}
BuiltMap Build(const fs::path& path) { return Build(map::LoadMapFile(path.string())); }

size_t Triangles(const std::vector<MapDrawable>& drawables) {
  size_t total = 0;
  for (const MapDrawable& d : drawables) total += d.mesh.indices.size() / 3;
  return total;
}

uint32_t ExpectedClass(map::ObjectKind kind) {
  static constexpr uint32_t kClasses[] = {proto::OBJECT_CLASS_BUILDING, proto::OBJECT_CLASS_TREE,
                                          proto::OBJECT_CLASS_LANTERN, proto::OBJECT_CLASS_PARK,
                                          proto::OBJECT_CLASS_OBSTACLE};  // in map::ObjectKind's order
  return kClasses[static_cast<int>(kind)];
}

// The urban driving map with the most objects: the heaviest scene shipped.
fs::path DensestUrbanMap() {
  fs::path densest;
  size_t most = 0;
  for (const fs::path& path : ShippedMaps()) {
    // the paper's 12x12 driving maps; the guided study's larger ones are held to the same density below
    if (path.string().find("driving") == std::string::npos || path.string().find("guided") != std::string::npos ||
        path.stem().string().find("urban") == std::string::npos)
      continue;
    const size_t objects = map::LoadMapFile(path.string()).objects.size();
    if (objects > most) std::tie(most, densest) = std::pair(objects, path);
  }
  return densest;
}

TEST(MapDrawablesTest, EveryShippedMapBuildsWellFormedLabelledDrawables) {
  const std::vector<fs::path> maps = ShippedMaps();
  ASSERT_GE(maps.size(), 40u);
  for (const fs::path& path : maps) {
    SCOPED_TRACE(path.string());
    const BuiltMap built = Build(path);
    size_t labelled = 0;
    for (const MapDrawable& d : built.drawables) {
      ASSERT_FALSE(d.mesh.indices.empty());
      ASSERT_EQ(d.mesh.indices.size() % 3, 0u);
      for (uint32_t index : d.mesh.indices) ASSERT_LT(index, d.mesh.vertices.size());
      for (const Vertex& v : d.mesh.vertices) {
        ASSERT_NEAR(Eigen::Vector3f(v.normal[0], v.normal[1], v.normal[2]).norm(), 1.0f, 1e-3f);
        for (float c : v.color) ASSERT_TRUE(c >= 0.0f && c <= 1.0f);
        for (float p : v.position) ASSERT_TRUE(std::isfinite(p));
      }
      if (d.instance == kUnlabelled) {
        EXPECT_EQ(d.object_class, 0u);
        continue;
      }
      // Labelled objects come in map order with contiguous ids.
      ASSERT_LT(labelled, built.map.objects.size());
      const map::MapObject& object = built.map.objects[labelled];
      EXPECT_EQ(d.instance, kFirstInstance + labelled);
      EXPECT_EQ(d.object_class, ExpectedClass(object.kind));
      EXPECT_NEAR(d.world_from_model(0, 3), object.position.x(), 1e-4);
      EXPECT_NEAR(d.world_from_model(1, 3), object.position.y(), 1e-4);
      ++labelled;
    }
    EXPECT_EQ(labelled, built.map.objects.size());
  }
}

TEST(MapDrawablesTest, DensestMapsStayWithinTheTriangleBudget) {
  const fs::path densest = DensestUrbanMap();
  ASSERT_FALSE(densest.empty());
  for (const fs::path& path : {densest, kScenes / "tracking/hard_urban.map"}) {
    const BuiltMap built = Build(path);
    const size_t triangles = Triangles(built.drawables);
    std::cout << path.lexically_relative(kScenes).string() << ": " << built.map.objects.size() << " objects, "
              << built.drawables.size() << " drawables, " << triangles << " triangles\n";
    EXPECT_LT(triangles, kTriangleBudget) << path;
  }
}

// The guided-driving maps (scenes/driving/guided, 16x16 and 20x20 tiles) are
// larger than the 12x12 driving maps: they may hold more triangles, but no
// more per tile than the budget allows a 12x12 map.
TEST(MapDrawablesTest, LargerMapsStayWithinTheBudgetPerTile) {
  constexpr double kPerTile = kTriangleBudget / 144.0;
  size_t checked = 0;
  for (const fs::path& path : ShippedMaps()) {
    if (path.string().find("guided") == std::string::npos) continue;
    const BuiltMap built = Build(path);
    const double tiles = static_cast<double>(built.map.width) * built.map.height;
    EXPECT_LT(Triangles(built.drawables) / tiles, kPerTile) << path;
    ++checked;
  }
  EXPECT_GE(checked, 12u);
}

TEST(MapDrawablesTest, RefusesIdsBeyondSixteenBits) {
  const map::Map map = map::LoadMapFile((kScenes / "tracking/easy_urban.map").string());
  const map::RoadGraph graph(map);
  EXPECT_THROW(BuildMapDrawables(map, graph, kUnlabelled), std::invalid_argument);
  EXPECT_THROW(BuildMapDrawables(map, graph, 65535), std::invalid_argument);
  EXPECT_NO_THROW(BuildMapDrawables(map, graph, static_cast<InstanceId>(65536 - map.objects.size())));
}

TEST(MapDrawablesTest, ObjectMeshesMatchTheirShapes) {
  // Physics uses ShapeOf; the drawn object must be as tall and stand on the
  // footprint (a lantern's arm and a tree's crown may reach past it).
  for (map::ObjectKind kind : map::kObjectKinds) {
    SCOPED_TRACE(map::ObjectKindName(kind));
    const map::ObjectShape& shape = map::ShapeOf(kind);
    const Mesh mesh = MakeObjectMesh(kind, map::Surroundings::kUrban, 3);
    Eigen::Vector3f low = Eigen::Vector3f::Constant(1e9f), high = -low;
    for (const Vertex& v : mesh.vertices) {
      low = low.cwiseMin(Eigen::Vector3f(v.position[0], v.position[1], v.position[2]));
      high = high.cwiseMax(Eigen::Vector3f(v.position[0], v.position[1], v.position[2]));
    }
    EXPECT_LE(mesh.indices.size() / 3, 110u);
    EXPECT_NEAR(low.z(), 0.0f, 1e-5f);
    const double reach = std::max({shape.half_x, shape.half_y, shape.crown_radius});
    if (kind != map::ObjectKind::kLantern) {
      EXPECT_LE(high.head<2>().cwiseAbs().maxCoeff(), reach + 1e-4);
    }
    if (kind != map::ObjectKind::kPark) {  // a park's benches stand on its lawn
      EXPECT_NEAR(high.z(), shape.height, 1e-4);
    }
    EXPECT_NEAR(low.x(), -std::max(shape.half_x, shape.crown_radius), 1e-4);
  }
}

using Frame = testing::RenderedFrame;

// The map's drawables uploaded into a Renderer, ready to draw.
struct MapScene {
  BuiltMap built;
  std::unique_ptr<Renderer> renderer;
  std::vector<DrawItem> items;
  std::vector<uint32_t> unoccluded;

  MapScene(BuiltMap map, uint32_t max_width, uint32_t max_height) : built(std::move(map)) {
    std::vector<Mesh> meshes;
    for (const MapDrawable& d : built.drawables) {
      items.push_back({static_cast<MeshId>(meshes.size()), d.world_from_model, d.instance});
      meshes.push_back(d.mesh);
    }
    renderer = std::make_unique<Renderer>(meshes, max_width, max_height);
    unoccluded.resize(kFirstInstance + built.map.objects.size());
  }

  Frame Render(const CameraView& camera) {
    Frame frame(camera.width, camera.height);
    renderer->Render(camera, items, frame.Buffers(), unoccluded);
    return frame;
  }
};

CameraView View(const Eigen::Vector3f& eye, const Eigen::Vector3f& target, const Eigen::Vector3f& up, uint32_t width,
                uint32_t height) {
  CameraView camera;
  camera.world_from_camera = LookAt(eye, target, up);
  camera.width = width;
  camera.height = height;
  return camera;
}

// Straight down over the map's centre, north up, high enough to see it all.
CameraView TopDown(const map::Map& map, uint32_t width, uint32_t height) {
  const float tan_half = std::tan(30.0f * std::numbers::pi_v<float> / 180.0f);
  const Eigen::Vector2d half = map.HalfExtent();
  const auto altitude =
      static_cast<float>(1.05 * std::max(half.y() / tan_half, half.x() * height / (tan_half * width)));
  return View({0, 0, altitude}, {0, 0, 0}, {0, 1, 0}, width, height);
}

// 15 m up, looking 60 degrees down at `target` from the south, like the UAV's gimbal camera.
CameraView UavView(const Eigen::Vector2d& target, uint32_t width, uint32_t height) {
  const float altitude = 15.0f, pitch = 60.0f * std::numbers::pi_v<float> / 180.0f;
  const Eigen::Vector3f aim(static_cast<float>(target.x()), static_cast<float>(target.y()), 0.0f);
  return View(aim + Eigen::Vector3f(0, -altitude / std::tan(pitch), altitude), aim, {0, 0, 1}, width, height);
}

// The pixel a world point projects to (x right, y down), as the renderer draws.
Eigen::Vector2f Project(const CameraView& camera, const Eigen::Vector3f& world) {
  const Eigen::Matrix4f clip_from_world =
      Perspective(camera.fov_y_deg, static_cast<float>(camera.width) / camera.height, camera.near_m, camera.far_m) *
      RigidInverse(camera.world_from_camera);
  const Eigen::Vector4f clip = clip_from_world * world.homogeneous();
  return {(clip.x() / clip.w() + 1.0f) / 2.0f * camera.width, (1.0f - clip.y() / clip.w()) / 2.0f * camera.height};
}

void SavePng(const Frame& frame, const std::string& path) {
  cv::Mat rgb(static_cast<int>(frame.height), static_cast<int>(frame.width), CV_8UC3,
              const_cast<uint8_t*>(frame.rgb.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  ASSERT_TRUE(cv::imwrite(path, bgr)) << path;
  std::cout << "wrote " << path << "\n";
}

class MapRenderTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { context_ = CreateGlContext(); }
  static void TearDownTestSuite() { context_.reset(); }
  static std::unique_ptr<GlContext> context_;
};
std::unique_ptr<GlContext> MapRenderTest::context_;

TEST_F(MapRenderTest, DesertAndUrbanLookDifferentFromAboveAndObjectsLandWhereTheyStand) {
  constexpr uint32_t kWidth = 640, kHeight = 360;
  std::map<std::string, Eigen::Vector3d> mean_ground;
  for (const std::string name : {"easy_desert", "easy_urban"}) {
    SCOPED_TRACE(name);
    MapScene scene(Build(kScenes / "tracking" / (name + ".map")), kWidth, kHeight);
    // The map's own colours, not the light: from this height the full look's
    // aerial perspective would tint both maps towards the sky.
    scene.renderer->SetLook(LookOf(conditions::Of(conditions::Preset::CLEAR_NOON, conditions::Quality::kFast)));
    const CameraView camera = TopDown(scene.built.map, kWidth, kHeight);
    const Frame frame = scene.Render(camera);
    SavePng(frame, "/tmp/sim4cv_map_" + name + "_top.png");

    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    size_t count = 0;
    std::map<InstanceId, Eigen::AlignedBox2f> seen;  // pixel bounds per instance
    for (uint32_t y = 0; y < kHeight; ++y) {
      for (uint32_t x = 0; x < kWidth; ++x) {
        const size_t i = frame.At(x, y);
        if (frame.mask[i] == kUnlabelled) {
          sum += Eigen::Vector3d(frame.rgb[3 * i], frame.rgb[3 * i + 1], frame.rgb[3 * i + 2]);
          ++count;
        } else {
          seen[frame.mask[i]].extend(Eigen::Vector2f(x + 0.5f, y + 0.5f));
        }
      }
    }
    ASSERT_GT(count, 0u);
    mean_ground[name] = sum / static_cast<double>(count);
    for (size_t k = 0; k < scene.built.map.objects.size(); ++k) {
      const map::MapObject& object = scene.built.map.objects[k];
      const auto id = static_cast<InstanceId>(kFirstInstance + k);
      const Eigen::Vector2f pixel = Project(camera, Eigen::Vector3f(static_cast<float>(object.position.x()),
                                                                    static_cast<float>(object.position.y()), 0.0f));
      const bool well_inside = pixel.x() > 8 && pixel.y() > 8 && pixel.x() < kWidth - 8 && pixel.y() < kHeight - 8;
      // Lanterns are thinner than a pixel from this high; everything else must show.
      if (well_inside && object.kind != map::ObjectKind::kLantern) {
        EXPECT_TRUE(seen.count(id)) << map::ObjectKindName(object.kind) << " " << id << " is missing from the mask";
      }
      // Seen from above, an object's silhouette covers its own footing, except
      // a lantern's: its pole is thinner than a pixel and its lamp 1.1 m aside.
      if (seen.count(id)) {
        const float pixels_per_metre =
            (Project(camera, Eigen::Vector3f(1, 0, 0)) - Project(camera, Eigen::Vector3f::Zero())).norm();
        const float slack = 2.0f + (object.kind == map::ObjectKind::kLantern ? 1.5f * pixels_per_metre : 0.0f);
        Eigen::AlignedBox2f box = seen[id];
        box.extend(box.min() - Eigen::Vector2f::Constant(slack)).extend(box.max() + Eigen::Vector2f::Constant(slack));
        EXPECT_TRUE(box.contains(pixel)) << map::ObjectKindName(object.kind) << " " << id << " projects to "
                                         << pixel.transpose() << ", its pixels span " << box.min().transpose() << " .. "
                                         << box.max().transpose();
      }
    }
    if (name == "easy_urban") {
      EXPECT_GT(seen.size(), scene.built.map.objects.size() / 2);
    }
  }
  const Eigen::Vector3d desert = mean_ground["easy_desert"], urban = mean_ground["easy_urban"];
  std::cout << "mean ground RGB: desert " << desert.transpose() << ", urban " << urban.transpose() << "\n";
  EXPECT_GT((desert - urban).cwiseAbs().sum(), 120.0);
  EXPECT_GT(desert.x(), desert.z() + 40);  // sand: warm
  EXPECT_GT(urban.y(), urban.x() + 10);    // grass: green
}

// Every tile kind, at the smallest tile size the format allows: the
// asphalt must cover every lane from side to side, with no gap where tiles
// meet or where junction fans and dead-end caps join the lanes.
TEST_F(MapRenderTest, AsphaltCoversEveryLaneOfEveryTileKind) {
  const map::Map map = map::ParseMap(R"(sim4cv-map 1
name every_kind
tile_size 12
surroundings urban
grid 6 5
.#....
####..
.#.###
.#.#..
.###..
end
)");
  const map::RoadGraph graph(map);
  constexpr uint32_t kWidth = 1280, kHeight = 720;
  MapScene scene(Build(map), kWidth, kHeight);
  const CameraView camera = TopDown(map, kWidth, kHeight);
  const Frame frame = scene.Render(camera);
  SavePng(frame, "/tmp/sim4cv_map_every_kind_top.png");
  const float altitude = camera.world_from_camera(2, 3);
  size_t checked = 0;
  for (const map::LaneSegment& lane : graph.segments()) {
    for (double s = 0.0; s <= lane.length(); s += 0.25) {
      const map::LanePoint at = graph.At(lane.id, s);
      for (double lateral : {-1.8, 0.0, 1.8}) {
        const Eigen::Vector2d p = at.position + lateral * Eigen::Vector2d(-std::sin(at.heading), std::cos(at.heading));
        const Eigen::Vector2f pixel =
            Project(camera, Eigen::Vector3f(static_cast<float>(p.x()), static_cast<float>(p.y()), 0.0f));
        const float depth = frame.depth[frame.At(static_cast<uint32_t>(pixel.x()), static_cast<uint32_t>(pixel.y()))];
        // The optical axis is vertical: depth is the altitude less the surface's height.
        ASSERT_NEAR(altitude - depth, 0.055f, 0.02f)
            << "no asphalt or paint under segment " << lane.id << " at s " << s << ", lateral " << lateral;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 1000u);
}

// Where the road is most complex: the lane point nearest the centre of the
// map's first crossroads, else of its first T-junction, else of its first
// curve that joins another curve, else of its first curve.
Eigen::Vector2d BusiestRoadPoint(const map::Map& map) {
  const auto curve_next_to_curve = [&](map::TileCoord t) {
    if (map.KindAt(t) != map::TileKind::kCurve) return false;
    return std::any_of(map::kEdges.begin(), map::kEdges.end(), [&](map::Edge e) {
      return map::Has(map.ConnectionsAt(t), e) && map.KindAt(map::Neighbour(t, e)) == map::TileKind::kCurve;
    });
  };
  const std::vector<std::function<bool(map::TileCoord)>> wishes = {
      [&](map::TileCoord t) { return map.KindAt(t) == map::TileKind::kCrossroads; },
      [&](map::TileCoord t) { return map.KindAt(t) == map::TileKind::kTJunction; }, curve_next_to_curve,
      [&](map::TileCoord t) { return map.KindAt(t) == map::TileKind::kCurve; }};
  for (const auto& wanted : wishes) {
    for (size_t i = 0; i < map.road.size(); ++i) {
      if (wanted(map.CoordOf(i))) return map::RoadGraph(map).Nearest(map.TileCentre(map.CoordOf(i))).lane.position;
    }
  }
  return map::RoadGraph(map).Nearest({0, 0}).lane.position;
}

// The UAV's view of the road: asphalt at the image centre, at the slant
// range, and painted lines in view.
void ExpectUavViewOfRoad(const fs::path& path, const std::string& png) {
  constexpr uint32_t kWidth = 640, kHeight = 360;
  MapScene scene(Build(path), kWidth, kHeight);
  const Frame frame = scene.Render(UavView(BusiestRoadPoint(scene.built.map), kWidth, kHeight));
  SavePng(frame, png);
  const size_t centre = frame.At(kWidth / 2, kHeight / 2);
  EXPECT_EQ(frame.mask[centre], kUnlabelled);
  // 4 cm of asphalt above the ground shortens the slant range a little.
  EXPECT_NEAR(frame.depth[centre], 15.0f / std::sin(60.0f * std::numbers::pi_v<float> / 180.0f), 0.2f);
  EXPECT_LT(frame.rgb[3 * centre] + frame.rgb[3 * centre + 1] + frame.rgb[3 * centre + 2], 3 * 110) << "not asphalt";
  size_t paint = 0;
  for (size_t i = 0; i < frame.mask.size(); ++i) {
    if (frame.mask[i] == kUnlabelled &&
        std::min({frame.rgb[3 * i], frame.rgb[3 * i + 1], frame.rgb[3 * i + 2]}) > 190) {
      ++paint;
    }
  }
  EXPECT_GT(paint, 500u) << "painted lines should show";
}

TEST_F(MapRenderTest, UavSeesTheHardTrackingMapsBends) {
  ExpectUavViewOfRoad(kScenes / "tracking/hard_urban.map", "/tmp/sim4cv_map_hard_urban_bend_uav.png");
}

TEST_F(MapRenderTest, UavSeesACrossroadsWithCrosswalks) {
  ExpectUavViewOfRoad(kScenes / "driving/test/01_urban.map", "/tmp/sim4cv_map_crossroads_uav.png");
}

TEST_F(MapRenderTest, DensestUrbanMapRendersQuickly) {
  constexpr uint32_t kWidth = 320, kHeight = 180;
  constexpr int kFrames = 30;
  MapScene scene(Build(DensestUrbanMap()), kWidth, kHeight);
  // The UAV's view, and the worst case: the whole map in view at once.
  const std::pair<std::string, CameraView> views[] = {
      {"uav", UavView(BusiestRoadPoint(scene.built.map), kWidth, kHeight)},
      {"whole_map", TopDown(scene.built.map, kWidth, kHeight)}};
  for (const auto& [name, camera] : views) {
    Frame frame = scene.Render(camera);  // warm up: first-use costs
    const FrameBuffers buffers = frame.Buffers();
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < kFrames; ++i) scene.renderer->Render(camera, scene.items, buffers, scene.unoccluded);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() / kFrames;
    std::cout << "densest urban map (" << Triangles(scene.built.drawables) << " triangles), 320x180 " << name
              << " view: " << ms << " ms per frame\n";
    RecordProperty(name + "_ms_per_frame", std::to_string(ms));
    SavePng(frame, "/tmp/sim4cv_map_densest_" + name + "_320.png");
    EXPECT_LT(ms, 2500.0);  // a sanity bound that holds beside a parallel build; bench/ measures the speed
  }
}

}  // namespace
}  // namespace sim4cv::render
