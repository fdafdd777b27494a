// What walkers cost to draw at eye level: the same street-level view of N
// walkers (4-24 m ahead, spread across 10 m, headings and gait phases
// varied) rendered with the packaged people (docs/assets.md), the same
// without their far level of detail, and with the procedural box figures,
// frame by frame in turn so the machine's drift weighs on all alike. RGB + depth + mask read back plus each walker's
// unoccluded silhouette (as the daemon does for boxes), full look at clear noon.
//   sim4cv_bench_walkers [--walkers N] [--frames N] [--width W] [--height H]
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/stats.h"
#include "protocol/conditions.h"
#include "server/common/diagnostics.h"
#include "server/render/camera_math.h"
#include "server/render/gl_context.h"
#include "server/render/look.h"
#include "server/render/mesh_builder.h"
#include "server/render/people_bundle.h"
#include "server/render/renderer.h"
#include "server/render/walker_looks.h"
#include "sim4cv.pb.h"

namespace {

using namespace sim4cv;
using namespace sim4cv::render;

struct Street {
  std::vector<Mesh> meshes;
  std::vector<DrawItem> items;
  uint64_t triangles_drawn = 0;
};

// A ground plane and `walkers` walkers drawn by a WalkerLooks of `people`.
Street MakeStreet(const std::vector<Person>& people, int walkers, bool far_meshes = true) {
  Street street;
  street.meshes.push_back(MakeGroundPlane(100.0f, {0.4f, 0.4f, 0.42f}));
  street.items.push_back({0, Eigen::Matrix4f::Identity(), kUnlabelled});
  const WalkerLooks looks(
      [&](Mesh mesh) {
        street.meshes.push_back(std::move(mesh));
        return static_cast<MeshId>(street.meshes.size() - 1);
      },
      people);
  for (int i = 0; i < walkers; ++i) {
    const Eigen::Vector2d position(4.0 + 20.0 * i / std::max(1, walkers - 1), -5.0 + 10.0 * ((i * 7) % 11) / 10.0);
    const double heading = 0.9 * i;
    Eigen::Matrix4f ground = Eigen::Matrix4f::Identity();
    ground.topLeftCorner<3, 3>() = Eigen::AngleAxisf(static_cast<float>(heading), Eigen::Vector3f::UnitZ()).matrix();
    ground.block<3, 1>(0, 3) = Eigen::Vector3f(static_cast<float>(position.x()), static_cast<float>(position.y()), 0);
    looks.Append(street.items, static_cast<InstanceId>(1 + i), ground, position, heading, 1.4);
  }
  for (DrawItem& item : street.items) {
    item.previous_world_from_model = item.world_from_model;
    if (!far_meshes) item.far_mesh = kNoFarMesh;
    street.triangles_drawn += street.meshes[item.mesh].indices.size() / 3;
  }
  return street;
}

int Flag(int argc, char** argv, const std::string& name, int fallback) {
  for (int i = 1; i + 1 < argc; ++i) {
    if (argv[i] == name) return std::atoi(argv[i + 1]);
  }
  return fallback;
}

}  // namespace

int main(int argc, char** argv) {
  const int walkers = Flag(argc, argv, "--walkers", 12), frames = Flag(argc, argv, "--frames", 300);
  const auto width = static_cast<uint32_t>(Flag(argc, argv, "--width", 640));
  const auto height = static_cast<uint32_t>(Flag(argc, argv, "--height", 480));
  const auto context = CreateGlContext();
  diagnostics::SetMinLevel(diagnostics::Level::kError);  // the procedural street warns that it has no people
  std::vector<Street> streets;
  streets.push_back(MakeStreet(PeopleMeshes(), walkers));
  streets.push_back(MakeStreet(PeopleMeshes(), walkers, false));
  streets.push_back(MakeStreet({}, walkers));
  diagnostics::SetMinLevel(diagnostics::Level::kInfo);
  const char* names[] = {"packaged people", "  without far LOD", "procedural figures"};
  std::vector<std::unique_ptr<Renderer>> renderers;
  for (const Street& street : streets) {
    renderers.push_back(std::make_unique<Renderer>(street.meshes, width, height));
    renderers.back()->SetLook(LookOf(conditions::Of(conditions::Preset::CLEAR_NOON)));
  }
  CameraView camera;
  camera.world_from_camera = LookAt({0, 0, 1.6f}, {10, 0, 0.9f}, Eigen::Vector3f::UnitZ());
  camera.previous_world_from_camera = camera.world_from_camera;
  camera.width = width;
  camera.height = height;
  std::vector<uint8_t> rgb(std::size_t{width} * height * 3);
  std::vector<float> depth(std::size_t{width} * height);
  std::vector<uint16_t> mask(std::size_t{width} * height);
  FrameBuffers out{};
  out[*channels::IndexOf(proto::CHANNEL_RGB)] = rgb.data();
  out[*channels::IndexOf(proto::CHANNEL_DEPTH)] = reinterpret_cast<uint8_t*>(depth.data());
  out[*channels::IndexOf(proto::CHANNEL_MASK)] = reinterpret_cast<uint8_t*>(mask.data());
  std::vector<uint32_t> unoccluded(walkers + 1);
  std::vector<std::vector<double>> ms(streets.size());
  for (int frame = -10; frame < frames; ++frame) {  // ten warm-up frames
    for (std::size_t s = 0; s < streets.size(); ++s) {
      const auto start = std::chrono::steady_clock::now();
      renderers[s]->Render(camera, streets[s].items, out, unoccluded);
      const std::chrono::duration<double, std::milli> took = std::chrono::steady_clock::now() - start;
      if (frame >= 0) ms[s].push_back(took.count());
    }
  }
  std::printf("walkers: %d at eye level, %ux%u, %d frames each, full look at clear noon\n", walkers, width, height,
              frames);
  for (std::size_t s = 0; s < streets.size(); ++s) {
    const bench::Summary summary = bench::Summarize(ms[s]);
    std::printf("%-19s %7llu triangles in the items (full meshes), median %.3f ms, p99 %.3f ms\n", names[s],
                static_cast<unsigned long long>(streets[s].triangles_drawn), summary.median, summary.p99);
  }
  return 0;
}
