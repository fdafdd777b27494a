// Physics and rendering cost, in-process, without transports:
//   1. physics steps per second of the scene's World (car + camera UAV), no rendering;
//   2. physics real-time factor of one car and four UAVs (the paper's four
//      trackers each flying its own UAV) at 240 Hz: the scene's World with
//      three UAVs spawned, all following the car;
//   3. frames rendered per second (RGB + depth + mask read back, boxes) from the UAV camera,
//      then each further channel's added cost (protocol/channels.h), RGB alone, and each channel
//      beside RGB alone.
//   4. the cost of the look (look.h): rgb+depth+mask with --quality fast, then full without
//      shadows, then full (the default), then full with sensor noise, in the conditions asked for.
//   5. the cost of each camera effect (protocol/effects.h) on top of that look, and of all at once.
//   sim4cv_bench_sim_render [--map FILE] [--width W] [--height H] [--steps N] [--frames N]
//                           [--traffic-cars N] [--traffic-parked N] [--traffic-pedestrians N] [--traffic-lights on|off]
//                           [--conditions PRESET] [--quality full|fast]
#include <array>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/stats.h"
#include "protocol/channels.h"
#include "protocol/conditions.h"
#include "protocol/effects.h"
#include "server/render/gl_context.h"
#include "server/render/ground_truth.h"
#include "server/render/renderer.h"
#include "server/render/scene_graphics.h"
#include "server/sim/world.h"

namespace {

using namespace sim4cv;
using Clock = std::chrono::steady_clock;
constexpr double kDt = 1.0 / 240.0;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// The scene's World with three more UAVs spawned, each filming the car from
// its own altitude like the scene's camera UAV: one car and four UAVs (the
// paper's four trackers each flying its own UAV), all in the full map.
double CarAndFourUavsRealTimeFactor(const sim::Scene& scene, int steps) {
  sim::World world(scene);
  sim::State state = world.InitialState();
  const sim::Entity& camera_uav = *state.Find(sim::kUavEntityId);
  for (int i = 1; i < 4; ++i) {
    sim::SpawnPose pose{camera_uav.body.position + Eigen::Vector3d(3.0 * i, 0.0, 2.0 * i), camera_uav.body.Yaw()};
    const uint32_t id = world.Spawn(state, sim::EntityKind::kUav, "", pose);
    sim::UavOrder follow = camera_uav.uav_order;
    follow.altitude += 2.0 * i;
    world.SetUavOrder(state, id, follow);
  }
  const auto start = Clock::now();
  for (int step = 0; step < steps; ++step) world.Step(state, kDt);
  return steps * kDt / Seconds(Clock::now() - start);
}

constexpr channels::ChannelSet kBaseChannels =
    channels::Bit(proto::CHANNEL_RGB) | channels::Bit(proto::CHANNEL_DEPTH) | channels::Bit(proto::CHANNEL_MASK);

// Times the frames of the scene's first camera at `states` (the world stepped
// as at 30 Hz, recorded once, so every Run renders the same frames and runs
// compare), rendering the pixel channels of a set (boxes whenever the set
// has MASK), read back as the daemon does.
struct RenderTimer {
  const std::vector<sim::State>& states;
  render::SceneGraphics& graphics;
  render::Renderer& renderer;
  uint32_t width, height;

  // A look and camera effects to render the frames in.
  struct Variant {
    render::Look look;
    effects::CameraEffects effects;
  };

  bench::Summary Run(channels::ChannelSet set) { return Interleaved(set, {{look, {}}}).front(); }

  // Each frame rendered once per entry of `variants` in turn, so that the
  // machine's drift (a noisy neighbour, the clock) weighs on all alike.
  std::vector<bench::Summary> Interleaved(channels::ChannelSet set, const std::vector<Variant>& variants) {
    std::array<std::vector<uint8_t>, channels::kPixelChannelCount> planes;
    render::FrameBuffers buffers{};
    for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
      if (!channels::Has(set, channels::kPixelChannels[i].id)) continue;
      planes[i].resize(std::size_t{width} * height * channels::kPixelChannels[i].bytes_per_pixel);
      buffers[i] = planes[i].data();
    }
    const bool boxes = channels::Has(set, proto::CHANNEL_MASK);
    const auto* mask = reinterpret_cast<const uint16_t*>(planes[*channels::IndexOf(proto::CHANNEL_MASK)].data());
    std::vector<uint32_t> unoccluded(boxes ? graphics.instance_id_bound() : 0);
    std::vector<render::GroundTruthBox> found;
    render::BoxExtractor extractor;
    std::vector<std::vector<double>> frame_ms(variants.size());
    for (auto& times : frame_ms) times.reserve(states.size());
    const sim::CameraSpec& camera = scene_camera;
    render::CameraView previous = graphics.CameraAt(camera, states.front());
    for (const sim::State& state : states) {
      // Updating the graphics is part of every frame's cost; it is done once
      // (a second Update would make this state its own previous one).
      const auto update_start = Clock::now();
      graphics.Update(state);
      renderer.SetHeadlights(graphics.headlights());
      render::CameraView view = graphics.CameraAt(camera, state);
      view.previous_world_from_camera = previous.world_from_camera;
      const auto update = Clock::now() - update_start;
      for (std::size_t v = 0; v < variants.size(); ++v) {
        const auto start = Clock::now() - update;
        renderer.SetLook(variants[v].look);
        view.effects = variants[v].effects;
        renderer.Render(view, graphics.draw_items(), buffers, unoccluded);
        if (boxes) {
          auto& labelled = graphics.labelled_objects();
          for (auto& object : labelled) object.unoccluded_pixels = unoccluded[object.instance];
          extractor.Extract(mask, width, height, labelled, found);
        }
        frame_ms[v].push_back(Seconds(Clock::now() - start) * 1e3);
      }
      previous = view;
    }
    std::vector<bench::Summary> summaries;
    for (const auto& times : frame_ms) summaries.push_back(bench::Summarize(times));
    return summaries;
  }
  const sim::CameraSpec& scene_camera;
  render::Look look;  // of Run
};

}  // namespace

int main(int argc, char** argv) {
  uint32_t width = 320, height = 180;
  int steps = 24000, frames = 2000;
  std::string map_file;
  traffic::TrafficConfig traffic;  // none unless asked for (lights only on urban maps, as in the daemon)
  conditions::Conditions look_conditions;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--map") map_file = argv[i + 1];
    if (flag == "--traffic-cars") traffic.moving_cars = std::stoi(argv[i + 1]);
    if (flag == "--traffic-parked") traffic.parked_cars = std::stoi(argv[i + 1]);
    if (flag == "--traffic-pedestrians") traffic.pedestrians = std::stoi(argv[i + 1]);
    if (flag == "--traffic-lights") traffic.traffic_lights = std::string(argv[i + 1]) == "on";
    if (flag == "--width") width = static_cast<uint32_t>(std::stoi(argv[i + 1]));
    if (flag == "--height") height = static_cast<uint32_t>(std::stoi(argv[i + 1]));
    if (flag == "--steps") steps = std::stoi(argv[i + 1]);
    if (flag == "--frames") frames = std::stoi(argv[i + 1]);
    if (flag == "--conditions") look_conditions = conditions::Of(*conditions::FindByName(argv[i + 1]));
    if (flag == "--quality") look_conditions.quality = *conditions::FindQuality(argv[i + 1]);
  }
  sim::Scene scene =
      map_file.empty() ? sim::DefaultScene(width, height) : sim::SceneFromMap(map_file, "", 6.0f, width, height);
  sim::AddTraffic(scene, traffic);
  sim::World world(scene);
  sim::State state = world.InitialState();

  const auto physics_start = Clock::now();
  for (int i = 0; i < steps; ++i) world.Step(state, kDt);
  const double physics_seconds = Seconds(Clock::now() - physics_start);
  std::printf("scene '%s'\n", scene.name.c_str());
  std::printf("physics (car + camera UAV): %d steps of 1/240 s in %.3f s: %.0f steps/s (real-time factor %.0fx)\n",
              steps, physics_seconds, steps / physics_seconds, steps * kDt / physics_seconds);
  std::printf("physics (car + 4 UAVs, 240 Hz): real-time factor %.0fx\n", CarAndFourUavsRealTimeFactor(scene, steps));

  auto gl = render::CreateGlContext();
  gl->MakeCurrent();
  render::SceneGraphics graphics(scene);
  render::Renderer renderer(graphics.meshes(), width, height);
  renderer.SetLamps(graphics.lamps());
  std::size_t triangles = 0;
  for (const auto& mesh : graphics.meshes()) triangles += mesh.indices.size() / 3;
  std::printf("render: %ux%u, %zu triangles in the scene, renderer %s\n", width, height, triangles,
              gl->RendererName().c_str());
  const render::Look look = render::LookOf(look_conditions);
  renderer.SetLook(look);
  std::printf("render: conditions %s\n", conditions::Describe(look_conditions).c_str());
  std::vector<sim::State> states;
  states.reserve(static_cast<std::size_t>(frames));
  for (int i = 0; i < frames; ++i) {
    for (int s = 0; s < 8; ++s) world.Step(state, kDt);  // the scene moves as it does at 30 Hz
    states.push_back(state);
  }
  RenderTimer timer{states, graphics, renderer, width, height, scene.cameras[0], look};
  const bench::Summary base = timer.Run(kBaseChannels);
  std::printf(
      "render: %d frames (rgb,depth,mask read back, boxes): median %.3f ms, p99 %.3f ms, max %.3f ms: "
      "%.0f fps\n",
      frames, base.median, base.p99, base.max, 1e3 / base.mean);
  // Each further channel's cost: the same frames with it added (docs/benchmarks.md).
  for (const channels::ChannelInfo& info : channels::kPixelChannels) {
    if (channels::Has(kBaseChannels, info.id)) continue;
    const bench::Summary with = timer.Run(kBaseChannels | channels::Bit(info.id));
    std::printf("render: + %-8s median %.3f ms (%+.3f ms), p99 %.3f ms\n", std::string(info.name).c_str(), with.median,
                with.median - base.median, with.p99);
  }
  const bench::Summary rgb_only = timer.Run(channels::Bit(proto::CHANNEL_RGB));
  std::printf("render: rgb alone (no boxes) median %.3f ms\n", rgb_only.median);
  // ... and each channel beside RGB alone: what a client asking for RGB and one more channel pays.
  for (const channels::ChannelInfo& info : channels::kPixelChannels) {
    if (info.id == proto::CHANNEL_RGB) continue;
    const bench::Summary with = timer.Run(channels::Bit(proto::CHANNEL_RGB) | channels::Bit(info.id));
    std::printf("render: rgb + %-8s median %.3f ms (%+.3f ms), p99 %.3f ms\n", std::string(info.name).c_str(),
                with.median, with.median - rgb_only.median, with.p99);
  }

  // What the look costs: the same frames in the flat look, and in the full look without shadows.
  render::Look fast = look;
  fast.full = false;
  fast.shadows = false;
  render::Look unshadowed = look;
  unshadowed.shadows = false;
  render::Look full = look;
  full.full = true;
  render::Look noisy = full;
  noisy.noise_read = 3.0f;
  noisy.noise_shot = 1.5f;
  // Interleaved frame by frame, as below.
  const std::vector<bench::Summary> looks =
      timer.Interleaved(kBaseChannels, {{fast, {}}, {unshadowed, {}}, {full, {}}, {noisy, {}}});
  const char* look_names[] = {"fast", "full, no shadows", "full", "full + noise"};
  for (std::size_t i = 0; i < looks.size(); ++i) {
    std::printf("look: %-16s rgb,depth,mask median %.3f ms, p99 %.3f ms\n", look_names[i], looks[i].median,
                looks[i].p99);
  }

  // What each camera effect adds to the look asked for (rgb,depth,mask and
  // boxes): every frame rendered without effects, then with each, in turn.
  using effects::CameraEffects;
  using effects::Only;
  CameraEffects exposure_and_white = Only(&CameraEffects::white_balance_k, 4000);
  exposure_and_white.exposure_ev = 0.5;
  CameraEffects all = effects::WideAngleLens();
  all.antialias = 1;
  all.motion_blur = 0.5;
  all.white_balance_k = 4000;
  all.jpeg_quality = 60;
  const std::vector<std::pair<std::string, CameraEffects>> cases = {
      {"antialias", Only(&CameraEffects::antialias, 1)},     {"exposure+wb", exposure_and_white},
      {"motion blur", Only(&CameraEffects::motion_blur, 1)}, {"lens", effects::WideAngleLens()},
      {"jpeg 60", Only(&CameraEffects::jpeg_quality, 60)},   {"all", all}};
  std::vector<RenderTimer::Variant> variants = {{look, {}}};
  for (const auto& entry : cases) variants.push_back({look, entry.second});
  const std::vector<bench::Summary> timed = timer.Interleaved(kBaseChannels, variants);
  std::printf("effects: %-15s median %.3f ms, p99 %.3f ms\n", "none", timed[0].median, timed[0].p99);
  for (std::size_t i = 0; i < cases.size(); ++i) {
    std::printf("effects: %-15s median %.3f ms (%+.3f ms), p99 %.3f ms\n", cases[i].first.c_str(), timed[i + 1].median,
                timed[i + 1].median - timed[0].median, timed[i + 1].p99);
  }
  return 0;
}
