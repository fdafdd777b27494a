// Renders the gallery (docs/gallery.md): the same views of one moment of a
// map with traffic, in the flat look of --quality fast, in every conditions
// preset and with each camera effect, as PNGs. In-process (no daemon): a frame is a pure
// function of the world state, the camera and the conditions.
//   sim4cv_gallery --out DIR [--map FILE] [--width W] [--height H] [--steps N]
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "protocol/conditions.h"
#include "protocol/effects.h"
#include "server/render/camera_math.h"
#include "server/render/gl_context.h"
#include "server/render/renderer.h"
#include "server/render/scene_graphics.h"
#include "server/sim/world.h"

namespace {

using namespace sim4cv;

cv::Mat Save(const std::filesystem::path& path, const std::vector<uint8_t>& rgb, uint32_t width, uint32_t height) {
  cv::Mat image(static_cast<int>(height), static_cast<int>(width), CV_8UC3, const_cast<uint8_t*>(rgb.data()));
  cv::Mat bgr;
  cv::cvtColor(image, bgr, cv::COLOR_RGB2BGR);
  if (!cv::imwrite(path.string(), bgr)) throw std::runtime_error("cannot write " + path.string());
  return bgr;
}

}  // namespace

int main(int argc, char** argv) try {
  uint32_t width = 480, height = 270;
  int steps = 2400;
  std::string map_file = "scenes/driving/train/01_urban.map";
  std::filesystem::path out;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--out")
      out = argv[i + 1];
    else if (flag == "--map")
      map_file = argv[i + 1];
    else if (flag == "--width")
      width = static_cast<uint32_t>(std::stoi(argv[i + 1]));
    else if (flag == "--height")
      height = static_cast<uint32_t>(std::stoi(argv[i + 1]));
    else if (flag == "--steps")
      steps = std::stoi(argv[i + 1]);
    else
      throw std::runtime_error("unknown flag " + flag);
  }
  if (out.empty()) throw std::runtime_error("usage: sim4cv_gallery --out DIR [--map FILE] [--width W] [--height H]");
  std::filesystem::create_directories(out);

  sim::Scene scene = sim::SceneFromMap(map_file, "", 8.0f, width, height);
  traffic::TrafficConfig traffic;
  traffic.moving_cars = 12;
  traffic.parked_cars = 20;
  traffic.pedestrians = 16;
  sim::AddTraffic(scene, traffic);
  sim::World world(scene);
  sim::State state = world.InitialState();
  // One frame (1/30 s) before the moment shown: where things were, for the
  // flow that motion blur smears along.
  constexpr int kFrameSteps = 8;
  for (int i = 0; i < steps - kFrameSteps; ++i) world.Step(state, 1.0 / 240.0);
  const sim::State before = state;
  for (int i = 0; i < kFrameSteps; ++i) world.Step(state, 1.0 / 240.0);

  auto gl = render::CreateGlContext();
  gl->MakeCurrent();
  render::SceneGraphics graphics(scene);
  graphics.Update(before);
  std::vector<render::CameraView> previous;
  for (const sim::CameraSpec& camera : scene.cameras) previous.push_back(graphics.CameraAt(camera, before));
  graphics.Update(state);
  render::Renderer renderer(graphics.meshes(), width, height);
  renderer.SetLamps(graphics.lamps());
  renderer.SetHeadlights(graphics.headlights());
  std::vector<uint8_t> rgb(std::size_t{width} * height * 3);
  render::FrameBuffers buffers{};
  buffers[*channels::IndexOf(proto::CHANNEL_RGB)] = rgb.data();

  // The scene's cameras (the UAV chasing the car, first-person, chase) and
  // one at eye level 8 m from the first walker that is walking.
  std::vector<std::pair<std::string, render::CameraView>> views;
  for (const sim::CameraSpec& camera : scene.cameras) views.emplace_back(camera.name, graphics.CameraAt(camera, state));
  for (const traffic::Walker& walker : state.traffic.walkers) {
    if (walker.linear_velocity.norm() < 0.5) continue;
    const Eigen::Vector3f target = walker.position.cast<float>() + Eigen::Vector3f(0, 0, 1.0f);
    const Eigen::Vector3f side(-std::sin(static_cast<float>(walker.heading)),
                               std::cos(static_cast<float>(walker.heading)), 0);
    render::CameraView view = views.front().second;
    view.world_from_camera =
        render::LookAt(target + 8.0f * side + Eigen::Vector3f(2.0f, 0, 0.6f), target, Eigen::Vector3f::UnitZ());
    views.emplace_back("walkers", view);
    break;
  }
  std::vector<cv::Mat> rows;  // one per look, the views side by side: sheet.png
  for (std::size_t i = 0; i < views.size(); ++i) {
    views[i].second.previous_world_from_camera = i < previous.size()
                                                     ? previous[i].world_from_camera
                                                     : views[i].second.world_from_camera;  // the walker cam stands
  }
  const auto render_all = [&](const std::string& look_name, const render::Look& look,
                              const effects::CameraEffects& camera_effects = {}) {
    renderer.SetLook(look);
    std::vector<cv::Mat> row;
    for (auto& [name, view] : views) {
      view.effects = camera_effects;
      renderer.Render(view, graphics.draw_items(), buffers, {});
      const auto path = out / (name + "_" + look_name + ".png");
      row.push_back(Save(path, rgb, width, height));
      std::printf("%s\n", path.c_str());
    }
    rows.emplace_back();
    cv::hconcat(row, rows.back());
  };
  render_all("fast", render::LookOf(conditions::Of(conditions::Preset::CLEAR_NOON, conditions::Quality::kFast)));
  for (const conditions::PresetInfo& preset : conditions::kPresets) {
    render_all(std::string(preset.name), render::LookOf(conditions::Of(preset.preset)));
  }
  // Camera effects and domain randomisation.
  conditions::Conditions noisy = conditions::Of(conditions::Preset::CLEAR_NOON);
  noisy.noise_read = 3.0;
  noisy.noise_shot = 1.5;
  render_all("noise", render::LookOf(noisy));
  for (uint64_t draw = 0; draw < 3; ++draw) {
    render_all("randomised_" + std::to_string(draw), render::LookOf(conditions::Randomized(2026, draw, {})));
  }
  const render::Look noon = render::LookOf(conditions::Of(conditions::Preset::CLEAR_NOON));
  using effects::CameraEffects;
  using effects::Only;
  render_all("antialias", noon, Only(&CameraEffects::antialias, 1));
  render_all("exposure_plus_1ev", noon, Only(&CameraEffects::exposure_ev, 1));
  render_all("white_balance_3200k", noon, Only(&CameraEffects::white_balance_k, 3200));
  render_all("motion_blur", noon, Only(&CameraEffects::motion_blur, 1));
  render_all("lens", noon, effects::WideAngleLens());
  render_all("jpeg_15", noon, Only(&CameraEffects::jpeg_quality, 15));
  // A cheap action camera: lens, half-frame shutter, sensor noise, JPEG.
  CameraEffects action = effects::WideAngleLens();
  action.motion_blur = 0.5;
  action.jpeg_quality = 60;
  action.antialias = 1;
  render_all("action_camera", render::LookOf(noisy), action);
  cv::Mat sheet;
  cv::vconcat(rows, sheet);
  cv::imwrite((out / "sheet.png").string(), sheet);
  return 0;
} catch (const std::exception& error) {
  std::fprintf(stderr, "sim4cv_gallery: %s\n", error.what());
  return 2;
}
