// Physics and rendering cost, in-process, without transports:
//   1. physics steps per second of the scene's World (car + camera UAV), no rendering;
//   2. physics real-time factor of one car and four UAVs (the paper's four
//      trackers each flying its own UAV) at 240 Hz, built from the vehicle components;
//   3. frames rendered per second (RGB + depth + mask read back, boxes) from the UAV camera.
//   sim4cv_bench_sim_render [--map FILE] [--width W] [--height H] [--steps N] [--frames N]
#include <btBulletDynamicsCommon.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/stats.h"
#include "server/render/gl_context.h"
#include "server/render/ground_truth.h"
#include "server/render/renderer.h"
#include "server/render/scene_graphics.h"
#include "server/sim/vehicles/car.h"
#include "server/sim/vehicles/car_driver.h"
#include "server/sim/vehicles/quadcopter.h"
#include "server/sim/world.h"

namespace {

using namespace sim4cv;
using Clock = std::chrono::steady_clock;
constexpr double kDt = 1.0 / 240.0;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// One car on the scene's lane and four quadcopters holding stations around it.
double CarAndFourUavsRealTimeFactor(const sim::Scene& scene, int steps) {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
  world.setGravity(btVector3(0, 0, -9.81));
  btStaticPlaneShape ground_shape(btVector3(0, 0, 1), 0);
  btRigidBody ground(btRigidBody::btRigidBodyConstructionInfo(0, nullptr, &ground_shape));
  world.addRigidBody(&ground);
  const auto& lane = scene.car_lane;
  vehicles::Car car(world, scene.car.params, lane[0], std::atan2(lane[1].y() - lane[0].y(), lane[1].x() - lane[0].x()));
  vehicles::CarDriver driver(scene.car.params, vehicles::Polyline(lane, true), scene.car.cruise_speed);
  std::vector<std::unique_ptr<vehicles::Quadcopter>> uavs;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d position(lane[0].x() + 5.0 * i, lane[0].y() - 10.0, 15.0);
    uavs.push_back(std::make_unique<vehicles::Quadcopter>(world, scene.uav.params, position, 0.0));
  }
  const auto start = Clock::now();
  for (int step = 0; step < steps; ++step) {
    car.SetControls(driver.Update(car.State(), kDt));
    car.Update(kDt);
    const Eigen::Vector3d target = car.State().position;
    for (int i = 0; i < 4; ++i) {
      uavs[static_cast<std::size_t>(i)]->SetCommand(vehicles::QuadcopterCommand::Hold(
          target + Eigen::Vector3d(-8.0 + 3.0 * i, -3.0, 15.0), 0.0, car.State().linear_velocity));
      uavs[static_cast<std::size_t>(i)]->Update(kDt);
    }
    world.stepSimulation(kDt, 0);
  }
  const double seconds = Seconds(Clock::now() - start);
  uavs.clear();
  world.removeRigidBody(&ground);
  return steps * kDt / seconds;
}

}  // namespace

int main(int argc, char** argv) {
  uint32_t width = 320, height = 180;
  int steps = 24000, frames = 2000;
  std::string map_file;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--map") map_file = argv[i + 1];
    if (flag == "--width") width = static_cast<uint32_t>(std::stoi(argv[i + 1]));
    if (flag == "--height") height = static_cast<uint32_t>(std::stoi(argv[i + 1]));
    if (flag == "--steps") steps = std::stoi(argv[i + 1]);
    if (flag == "--frames") frames = std::stoi(argv[i + 1]);
  }
  const sim::Scene scene =
      map_file.empty() ? sim::DefaultScene(width, height) : sim::SceneFromMap(map_file, "", 6.0f, width, height);
  sim::World world(scene);
  sim::State state = world.InitialState();

  const auto physics_start = Clock::now();
  for (int i = 0; i < steps; ++i) world.Step(state, kDt);
  const double physics_seconds = Seconds(Clock::now() - physics_start);
  std::printf("scene '%s'\n", scene.name.c_str());
  std::printf("physics (car + camera UAV): %d steps of 1/240 s in %.3f s: %.0f steps/s (real-time factor %.0fx)\n",
              steps, physics_seconds, steps / physics_seconds, steps * kDt / physics_seconds);
  std::printf("physics (car + 4 UAVs, 240 Hz): real-time factor %.0fx\n", CarAndFourUavsRealTimeFactor(scene, steps));

  auto gl = render::CreateOsMesaContext();
  gl->MakeCurrent();
  render::SceneGraphics graphics(scene);
  render::Renderer renderer(graphics.meshes(), width, height);
  render::BoxExtractor extractor;
  std::vector<uint8_t> rgb(width * height * 3);
  std::vector<float> depth(width * height);
  std::vector<uint16_t> mask(width * height);
  std::vector<uint32_t> unoccluded(graphics.instance_id_bound());
  std::vector<render::GroundTruthBox> boxes;
  std::vector<double> frame_ms;
  frame_ms.reserve(static_cast<std::size_t>(frames));
  std::size_t triangles = 0;
  for (const auto& mesh : graphics.meshes()) triangles += mesh.indices.size() / 3;

  for (int i = 0; i < frames; ++i) {
    for (int s = 0; s < 8; ++s) world.Step(state, kDt);  // the scene moves as it does at 30 Hz
    const auto start = Clock::now();
    renderer.Render(graphics.CameraAt(0, state), graphics.DrawItems(state), {rgb.data(), depth.data(), mask.data()},
                    unoccluded);
    auto& labelled = graphics.labelled_objects();
    for (auto& object : labelled) object.unoccluded_pixels = unoccluded[object.instance];
    extractor.Extract(mask.data(), width, height, labelled, boxes);
    frame_ms.push_back(Seconds(Clock::now() - start) * 1e3);
  }
  const auto render = bench::Summarize(frame_ms);
  std::printf("render: %ux%u, %zu triangles in the scene, renderer %s\n", width, height, triangles,
              gl->RendererName().c_str());
  std::printf("render: %d frames (RGB+depth+mask read back, boxes): median %.3f ms, p99 %.3f ms, max %.3f ms: %.0f fps\n",
              frames, render.median, render.p99, render.max, 1e3 / render.mean);
  return 0;
}
