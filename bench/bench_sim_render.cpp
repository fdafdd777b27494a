// Physics steps per second (no rendering) and frames rendered per second
// (RGB + depth + mask + boxes) on the default scene, in-process.
//   sim4cv_bench_sim_render [--width W] [--height H] [--steps N] [--frames N]
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench/stats.h"
#include "server/render/gl_context.h"
#include "server/render/ground_truth.h"
#include "server/render/renderer.h"
#include "server/render/scene_graphics.h"
#include "server/sim/world.h"

namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

int main(int argc, char** argv) {
  uint32_t width = 320, height = 180;
  int steps = 24000, frames = 2000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    const int value = std::stoi(argv[i + 1]);
    if (flag == "--width") width = static_cast<uint32_t>(value);
    if (flag == "--height") height = static_cast<uint32_t>(value);
    if (flag == "--steps") steps = value;
    if (flag == "--frames") frames = value;
  }
  using namespace sim4cv;
  const sim::Scene scene = sim::DefaultScene(width, height);
  sim::World world(scene);
  sim::State state = world.InitialState();
  const double dt = 1.0 / 240.0;

  const auto physics_start = Clock::now();
  for (int i = 0; i < steps; ++i) world.Step(state, dt);
  const double physics_seconds = Seconds(Clock::now() - physics_start);
  std::printf("physics: %d steps of 1/240 s in %.3f s: %.0f steps/s (real-time factor %.0fx)\n", steps, physics_seconds,
              steps / physics_seconds, steps * dt / physics_seconds);

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
    for (int s = 0; s < 8; ++s) world.Step(state, dt);  // the scene moves as it does at 30 Hz
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
