// sim4cv_drive: the driving case study's C++ client (docs/driving.md, "C++
// driving client"). Each frame of the car's first-person camera goes through
// the waypoint network (ONNX, OpenCV's DNN) and the controller, and Controls
// go back to the car.
//
//   sim4cv_drive --model model.onnx --frames tcp://127.0.0.1:5000 --car car --camera ego_cam --add-camera --lockstep
//   sim4cv_drive --model model.onnx --frames shm:///sim4cv --car 1 --camera car_front --max-speed 8
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "driving/controller.h"
#include "driving/model_card.h"
#include "driving/waypoint_model.h"
#include "flags.h"
#include "sim4cv/client.h"

namespace {

using namespace sim4cv;
using Clock = std::chrono::steady_clock;

struct Options {
  std::string model, frames, controls, car, camera;
  // Unset: the model card's (model.json beside the model), else the paper's rule at 8 m/s.
  std::optional<double> max_speed;     // m/s, as sim4cv.driving drive and evaluate
  std::optional<double> steer_waypoint;  // 1: the paper's rule; 2 is steadier with a noisy first waypoint
  std::optional<double> steer_gain;    // 1: the paper's rule
  std::optional<double> turn_slowdown;  // 0: the paper's throttle
  std::optional<double> bend_correction;  // 0: the paper's rule
  std::optional<double> bend_limit;       // m; unset: no limit
  int goal = 0;
  bool left_lane = false;
  long frames_count = 0;  // 0: until Ctrl-C
  bool lockstep = false;
  bool add_camera = false;
};

using examples::ParseNumber;
using examples::UsageError;

volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

Options ParseArgs(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") throw UsageError("");
    if (flag == "--lockstep" || flag == "--add-camera") {
      (flag == "--lockstep" ? o.lockstep : o.add_camera) = true;
      continue;
    }
    if (i + 1 >= argc) throw UsageError("missing value after " + flag);
    const std::string value = argv[++i];
    if (flag == "--model") {
      o.model = value;
    } else if (flag == "--frames") {
      o.frames = value;
    } else if (flag == "--controls") {
      o.controls = value;
    } else if (flag == "--car") {
      o.car = value;
    } else if (flag == "--camera") {
      o.camera = value;
    } else if (flag == "--max-speed") {
      o.max_speed = ParseNumber(flag, value, 0.1, 100.0);
    } else if (flag == "--steer-waypoint") {
      o.steer_waypoint = ParseNumber(flag, value, 1, 4);
    } else if (flag == "--steer-gain") {
      o.steer_gain = ParseNumber(flag, value, 0.01, 10.0);
    } else if (flag == "--turn-slowdown") {
      o.turn_slowdown = ParseNumber(flag, value, 0.0, 100.0);
    } else if (flag == "--bend-correction") {
      o.bend_correction = ParseNumber(flag, value, 0.0, 1.0);
    } else if (flag == "--bend-limit") {
      o.bend_limit = ParseNumber(flag, value, 0.01, 100.0);
    } else if (flag == "--goal") {
      if (value != "-1" && value != "0" && value != "1")
        throw UsageError("--goal wants -1, 0 or 1, got '" + value + "'");
      o.goal = std::stoi(value);
    } else if (flag == "--lane") {
      if (value != "left" && value != "right") throw UsageError("--lane wants left or right, got '" + value + "'");
      o.left_lane = value == "left";
    } else if (flag == "--frames-count") {
      const double count = ParseNumber(flag, value, 0.0, 1e9);
      if (count != std::floor(count)) throw UsageError("--frames-count wants a whole number, got '" + value + "'");
      o.frames_count = static_cast<long>(count);
    } else {
      throw UsageError("unknown flag: " + flag);
    }
  }
  for (const auto& [flag, value] : {std::pair<const char*, const std::string*>{"--model", &o.model},
                                    {"--frames", &o.frames},
                                    {"--car", &o.car},
                                    {"--camera", &o.camera}}) {
    if (value->empty()) throw UsageError(std::string(flag) + " is required");
  }
  return o;
}

// The car named (or numbered) `car` in `world`; throws unless it is a car.
proto::EntityInfo FindCar(const proto::WorldInfo& world, const std::string& car) {
  std::string listing;
  for (const auto& e : world.entities()) {
    if (e.name() == car || std::to_string(e.id()) == car) {
      if (e.kind() != proto::ENTITY_KIND_CAR) {
        const std::string kind = e.kind() == proto::ENTITY_KIND_UAV ? "a UAV" : "no car";
        throw std::runtime_error("entity " + std::to_string(e.id()) + " ('" + e.name() + "') is " + kind +
                                 "; --car wants a car");
      }
      return e;
    }
    listing += (listing.empty() ? "" : ", ") + std::to_string(e.id()) + " ('" + e.name() + "')";
  }
  throw std::runtime_error("no entity is named or numbered '" + car + "'; the world holds " + listing);
}

// The camera the driving datasets are rendered with (docs/driving.md,
// "Camera"; sim4cv.driving_dataset.CAMERA_SETTINGS), mounted on `car`:
// car_front's geometry, 320x180, fov 60, 2.35 m ahead of the body's centre
// (just past the bumper), 0.3 m above it, 5 deg down.
CameraSetup FirstPersonCamera(const std::string& name, const std::string& car) {
  return {.name = name,
          .mounted_on = car,
          .width = 320,
          .height = 180,
          .fov_y_deg = 60,
          .pitch_down_deg = 5,
          .x = 2.35,
          .z = 0.3};
}

// The default controls address: the daemon's UDP port (Welcome.transports)
// on the --frames host (127.0.0.1 for shm://); "" if it serves no UDP.
std::string DefaultControls(const proto::Welcome& welcome, const std::string& frames) {
  for (const auto& t : welcome.transports()) {
    if (t.kind() != proto::TRANSPORT_KIND_UDP) continue;
    std::string host = "127.0.0.1";
    const auto scheme = frames.find("://");
    const auto colon = frames.rfind(':');
    if (frames.rfind("shm://", 0) != 0 && scheme != std::string::npos && colon > scheme + 3) {
      host = frames.substr(scheme + 3, colon - scheme - 3);
    }
    return "udp://" + host + ":" + t.address();
  }
  return "";
}

std::optional<double> CarSpeed(const proto::State& state, uint32_t car) {
  for (const auto& e : state.entities()) {
    if (e.id() != car) continue;
    const auto& v = e.linear_velocity();
    return std::hypot(v.x(), v.y());  // as sim4cv.driving drive
  }
  return std::nullopt;
}

int Run(const Options& o) {
  driving::WaypointModel model(o.model);
  if (o.goal != 0 && !model.has_goal()) {
    throw std::runtime_error("--goal " + std::to_string(o.goal) + " needs a model with a 'goal' input; " + o.model +
                             " has none");
  }
  const std::optional<driving::ModelCard> card = driving::ReadModelCard(o.model);
  if (card) card->CheckModel(model.height(), model.width(), model.has_goal());
  std::string settings = "settings:";
  // A flag, else the card, else the default; each printed with where it came from.
  const auto choose = [&](const char* name, auto flag, auto from_card, auto fallback) {
    const char* source = flag ? "flag" : from_card ? "model card" : "default";
    const auto value = flag ? *flag : from_card ? *from_card : fallback;
    std::ostringstream line;
    line << " " << name << " " << value << " (" << source << (flag || !from_card ? std::string() : " " + card->path) << ")";
    settings += line.str();
    return value;
  };
  driving::ControllerParams params;
  params.steer_waypoint = choose("steer_waypoint", o.steer_waypoint,
                                 card ? card->steer_waypoint : std::nullopt, params.steer_waypoint);
  params.gain = choose("steer_gain", o.steer_gain, card ? card->steer_gain : std::nullopt, params.gain);
  params.slowdown = choose("turn_slowdown", o.turn_slowdown, card ? card->turn_slowdown : std::nullopt,
                           params.slowdown);
  params.bend = choose("bend_correction", o.bend_correction, card ? card->bend_correction : std::nullopt, params.bend);
  params.bend_limit = choose("bend_limit_m", o.bend_limit, card ? card->bend_limit_m : std::nullopt, params.bend_limit);
  const double max_speed = choose("speed_m_s", o.max_speed, card ? card->speed_m_s : std::nullopt, 8.0);
  const driving::Controller controller(params);
  std::printf("model %s: %dx%d RGB%s\n%s\n", o.model.c_str(), model.width(), model.height(),
              model.has_goal() ? ", goal input" : "", settings.c_str());

  Client frames;
  frames.Connect(o.frames, "sim4cv_drive");
  const bool lockstep_daemon = frames.welcome().mode() == proto::SIM_MODE_LOCKSTEP;
  if (o.lockstep && !lockstep_daemon) {
    throw std::runtime_error("--lockstep needs a daemon started with --mode lockstep; this one runs in realtime mode");
  }
  if (!o.lockstep && lockstep_daemon) {
    std::printf(
        "note: the daemon runs in lockstep mode: without --lockstep frames come only when another client "
        "steps\n");
  }
  const proto::WorldInfo world = frames.GetWorld();
  const proto::EntityInfo car = FindCar(world, o.car);
  bool camera_exists = false;
  std::string cameras;
  for (const auto& c : world.cameras()) {
    camera_exists |= c.name() == o.camera;
    cameras += (cameras.empty() ? "" : ", ") + c.name();
  }
  if (!camera_exists && !o.add_camera) {
    throw std::runtime_error("no camera is named '" + o.camera + "'; the world's cameras: " + cameras +
                             " (--add-camera adds a first-person one on the car)");
  }
  if (!camera_exists) {
    frames.AddCamera(FirstPersonCamera(o.camera, car.name()));
    std::printf("added camera '%s' on '%s': car_front's geometry, 320x180, fov 60, 5 deg down\n", o.camera.c_str(),
                car.name().c_str());
  }
  frames.Subscribe(o.camera, {proto::CHANNEL_RGB}, o.lockstep ? proto::DELIVERY_LOCKSTEP : proto::DELIVERY_NEWEST,
                   /*with_state=*/true);

  // Where Controls go. In lockstep they must go over the frames connection:
  // the daemon handles one connection's messages in order, so Controls sent
  // before the next Step are taken in before that Step advances the world.
  // Over a second connection (UDP) nothing orders the two: the Step could be
  // read first, the Controls would land a frame late or, from frame to
  // frame, sometimes late and sometimes not, and a lockstep run would no
  // longer be repeatable.
  std::string controls_address = o.lockstep ? o.frames : !o.controls.empty() ? o.controls : "";
  if (o.lockstep && !o.controls.empty() && o.controls != o.frames) {
    std::printf("note: --lockstep sends controls over the frames connection; --controls %s is not used\n",
                o.controls.c_str());
  }
  if (controls_address.empty()) controls_address = DefaultControls(frames.welcome(), o.frames);
  if (controls_address.empty()) {
    std::printf("note: the daemon serves no UDP; controls go over the frames connection\n");
    controls_address = o.frames;
  }
  std::unique_ptr<Client> own_controls;
  Client* controls = &frames;
  if (controls_address != o.frames) {
    own_controls = std::make_unique<Client>();
    own_controls->Connect(controls_address, "sim4cv_drive-controls");
    controls = own_controls.get();
  }
  std::printf("driving car %u '%s' from camera '%s' (frames %s, controls %s%s%s)\n", car.id(), car.name().c_str(),
              o.camera.c_str(), o.frames.c_str(), controls_address.c_str(), o.lockstep ? ", lockstep" : "",
              o.left_lane ? ", left lane: image flipped" : "");
  std::fflush(stdout);

  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  proto::Frame frame;
  cv::Mat flipped;
  long total = 0, second_frames = 0;
  double total_ms = 0, max_ms = 0, second_ms = 0;
  driving::DriveControls last{};
  std::optional<double> speed;
  const auto start = Clock::now();
  auto second_start = start;
  while (!g_stop && (o.frames_count == 0 || total < o.frames_count)) {
    if (o.lockstep) frames.Step();
    if (!frames.ReceiveFrame(frame)) {
      throw ConnectionError("no frame for 10 s" +
                            std::string(!o.lockstep && lockstep_daemon ? " (a lockstep daemon: pass --lockstep)" : ""));
    }
    const auto rgb = FindImage(frame, proto::CHANNEL_RGB);
    if (!rgb) throw std::runtime_error("frame " + std::to_string(frame.frame_id()) + " carries no RGB image");
    const cv::Mat image(static_cast<int>(rgb->height), static_cast<int>(rgb->width), CV_8UC3,
                        const_cast<uint8_t*>(rgb->data), rgb->stride);
    // --lane left, the paper's lane-change trick: a network trained in the
    // right lane sees the left lane as a right one in the mirrored image; its
    // waypoints are mirrored back (h negated), and so is the goal.
    if (o.left_lane) cv::flip(image, flipped, 1);
    const auto t0 = Clock::now();
    driving::Waypoints w =
        model.Predict(o.left_lane ? flipped : image, static_cast<float>(o.left_lane ? -o.goal : o.goal));
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (o.left_lane) {
      for (std::size_t i = 1; i < w.size(); i += 2) w[i] = -w[i];
    }
    // Over TCP and UDP the frame carries the state (with_state); shared
    // memory frames do not, so ask for it.
    speed = CarSpeed(frame.has_state() ? frame.state() : frames.GetState(), car.id());
    last = controller.FromWaypoints(w, speed, max_speed);
    controls->SendControls(car.id(), static_cast<float>(last.steering), static_cast<float>(last.throttle),
                           static_cast<float>(last.brake));
    ++total, ++second_frames;
    total_ms += ms, second_ms += ms, max_ms = std::max(max_ms, ms);
    const auto now = Clock::now();
    const double window = std::chrono::duration<double>(now - second_start).count();
    if (window >= 1.0) {
      std::printf("[%6.1f s] frames %ld  fps %.1f  inference %.2f ms  steering %+.3f  throttle %.3f  speed %.2f m/s\n",
                  std::chrono::duration<double>(now - start).count(), total, second_frames / window,
                  second_ms / second_frames, last.steering, last.throttle, speed.value_or(NAN));
      std::fflush(stdout);
      second_start = now, second_frames = 0, second_ms = 0;
    }
  }
  // The car keeps its last Controls until others come: leave it braking.
  controls->SendControls(car.id(), 0.f, 0.f, 1.f);
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf("drove %ld frames in %.2f s: %.1f fps, inference %.2f ms mean, %.2f ms max; left the car braking\n",
              total, seconds, seconds > 0 ? total / seconds : 0.0, total ? total_ms / total : 0.0, max_ms);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(ParseArgs(argc, argv));
  } catch (const UsageError& e) {
    if (*e.what() != '\0') std::cerr << "sim4cv_drive: " << e.what() << "\n";
    std::cerr << "usage: sim4cv_drive --model FILE.onnx --frames ADDRESS [--controls ADDRESS] --car NAME_OR_ID "
                 "--camera NAME [--add-camera] [--max-speed M/S] [--goal -1|0|1] [--lane left|right] "
                 "[--steer-waypoint 1-4] [--steer-gain G] [--turn-slowdown S] [--bend-correction C] [--bend-limit M] "
                 "[--frames-count N] [--lockstep]\n"
                 "  unset --max-speed, --steer-waypoint, --steer-gain, --turn-slowdown, --bend-correction, "
                 "--bend-limit: model.json beside the model, else 8, 1, 1, 0, 0, none\n"
                 "  ADDRESS: tcp://HOST:PORT, udp://HOST:PORT or shm://NAME; --controls defaults to the daemon's UDP "
                 "port\n";
    return 2;
  } catch (const ServerError& e) {
    std::cerr << "sim4cv_drive: sim4cvd refused: " << proto::ErrorCode_Name(e.code()) << ": " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "sim4cv_drive: " << e.what() << "\n";
    return 1;
  }
}
