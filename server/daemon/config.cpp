#include "server/daemon/config.h"

#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <sstream>
#include <type_traits>

#include "protocol/shm_sync.h"
#include "server/common/check.h"

namespace sim4cv::daemon {
namespace {

template <typename T>
T ParseNumber(const std::string& flag, const std::string& text, T low, T high) {
  // istream >> unsigned accepts "-1" and wraps it; refuse the sign instead.
  SIM4CV_THROW_UNLESS(std::is_signed_v<T> || text.find('-') == std::string::npos,
                      flag << " is " << text << "; it must be in [" << low << ", " << high << "]");
  std::istringstream in(text);
  T value{};
  in >> value;
  SIM4CV_THROW_UNLESS(in && in.eof(), flag << " expects a number, got '" << text << "'");
  SIM4CV_THROW_UNLESS(value >= low && value <= high,
                      flag << " is " << text << "; it must be in [" << low << ", " << high << "]");
  return value;
}

// "1,3,7": entity ids, each in [1, 65535].
std::vector<uint32_t> ParseIdList(const std::string& flag, const std::string& text) {
  std::vector<uint32_t> ids;
  std::istringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) ids.push_back(ParseNumber<uint32_t>(flag, item, 1, 65535));
  SIM4CV_THROW_UNLESS(!ids.empty(), flag << " is '" << text << "'; give entity ids separated by commas, e.g. 1");
  return ids;
}

// "rgb,depth": the pixel channels the shared-memory ring carries, as a channel set.
channels::ChannelSet ParseChannelList(const std::string& flag, const std::string& text) {
  channels::ChannelSet set = 0;
  for (std::size_t start = 0;;) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const channels::ChannelInfo* info = channels::FindByName(item);
    SIM4CV_THROW_UNLESS(info != nullptr, flag << " is '" << text << "'; '" << item << "' is not a channel: use "
                                              << channels::Names(channels::kAllPixels)
                                              << " (any of them, separated by commas), e.g. rgb");
    SIM4CV_THROW_UNLESS(!channels::Has(set, info->id), flag << " is '" << text << "'; it lists " << item << " twice");
    set |= channels::Bit(info->id);
    if (comma == std::string::npos) return set;
    start = comma + 1;
  }
}

// The --help lines that list the pixel channels, from the channel table.
std::string ChannelHelp() {
  std::string text;
  for (const channels::ChannelInfo& info : channels::kPixelChannels) {
    std::string name(info.name);
    name.resize(10, ' ');
    text += "                              " + name + std::string(info.summary) + "\n";
  }
  return text;
}

// One line per camera effect (protocol/effects.h), wrapped like the rest.
std::string EffectsHelp() {
  std::string text;
  for (const effects::EffectInfo& info : effects::kEffects) {
    std::ostringstream line;
    line << "  --" << info.flag << " V";
    std::string head = line.str();
    head.resize(28, ' ');
    std::ostringstream what;
    what << info.summary << "; " << info.min << " .. " << info.max;
    if (!info.unit.empty()) what << " " << info.unit;
    what << " (default " << info.off << ")";
    std::string words = what.str(), row = head;
    std::istringstream split(words);
    std::string word;
    while (split >> word) {
      if (row.size() + 1 + word.size() > 100) {
        text += row + "\n";
        row = std::string(28, ' ');
      }
      row += (row.back() == ' ' ? "" : " ") + word;
    }
    text += row + "\n";
  }
  return text;
}

// A loopback address: only this machine's processes reach it.
bool IsLoopback(const std::string& address) {
  return address.rfind("127.", 0) == 0 || address == "::1" || address == "localhost";
}

}  // namespace

uint32_t Config::substeps_per_frame() const {
  const double ratio = physics_hz / frame_hz;
  return static_cast<uint32_t>(std::lround(ratio));
}

std::string HelpText() {
  return R"(sim4cvd: the sim4cv simulation daemon. Steps vehicle physics with Bullet, renders camera
frames offscreen with OSMesa and serves them to clients (see docs/protocol.md).

Usage: sim4cvd [flags]

  --scene FILE              scene file to load (docs/scenes.md); default: the embedded default scene
  --map FILE                a tile map to load instead (docs/maps.md), e.g. scenes/tracking/easy_urban.map
  --route NAME              the map's closed route the target car drives (default: its first closed route)
  --maps-dir DIR            where a client's LoadMap finds maps by name (default: PREFIX/share/sim4cv/scenes
                            beside an installed daemon, else the source tree's scenes/)
  --car-speed M/S           the target car's set speed on a map (default 6; the paper uses 4, 6 and 8)
  --traffic-cars N          kinematic traffic cars driving a map's lanes (default 0)
  --traffic-parked N        cars parked at the kerb of a map's straight roads (default 0)
  --traffic-pedestrians N   pedestrians walking across a map's crosswalks (default 0)
  --traffic-lights on|off   traffic lights at the junctions of urban maps (default on; desert maps
                            never have them)
  --traffic-green S         seconds of green per junction axis (default 8)
  --traffic-yellow S        seconds of yellow after green (default 2)
  --traffic-all-red S       seconds both axes are red between (default 1)
  --traffic-seed N          the seed of the traffic's layout and choices (default: --seed)
  --seed N                  seed for every random choice of the simulation (default 1)
  --bind ADDRESS            address the TCP port listens on (default 127.0.0.1; 0.0.0.0 for all)
  --tcp-port N              TCP port; 0 picks any free port (default 0)
  --token-file FILE         the access token clients must show in Hello (docs/security.md); default:
                            a fresh random one. Either way it is written, readable only by this user,
                            to $XDG_RUNTIME_DIR/sim4cv/tcp-PORT.token (or ~/.cache/sim4cv/), where
                            this user's clients find it
  --no-auth                 admit clients without the token; only with loopback --bind and --http-bind
  --physics-hz N            physics steps per simulated second (default 240)
  --frame-hz N              frames per simulated second; physics-hz must be a multiple (default 30)
  --width N, --height N     camera resolution in pixels (default 320 x 180)
  --mode lockstep|realtime  lockstep: a frame advances when every lockstep client sent Step;
                            realtime: simulated time follows wall time, newest frame only (default lockstep)
  --max-message-bytes N     largest Envelope a client may send (default 2097152: a LoadMap's map
                            text, at most 1 MiB, and room to spare)
  --max-clients N           most simultaneous connections (default 64); with the daemon's own files
                            they must fit the descriptor limit (ulimit -n), raised if it can be
  --tcp-send-buffer N       kernel send buffer per TCP connection in bytes, 0 = kernel default
                            (default 262144: small, so slow newest-frame readers get fresh frames)
  --handshake-timeout-ms N  a TCP client must have sent its whole Hello this long after connecting
                            (default 10000; 0 = no limit)
  --message-timeout-ms N    a message a TCP client started must be complete within this (default
                            10000; 0 = no limit)
  --idle-timeout-ms N       a handshaken TCP client that neither sends nor receives anything for this
                            long is disconnected (default 0 = never: a lockstep client paused in a
                            debugger stays connected)
  --controls-timeout-ms N   a car driven by Controls that gets none for N ms of simulation time brakes
                            to a stop and is free for another client to drive (default 1000; 0 = never)
  --http-port N             serve the studio (docs/studio.md: live view, map, controls) and its
                            WebSocket transport on this HTTP port; 0 picks any free port (default
                            -1: off). Anyone who can reach it can drive the simulation
  --http-bind ADDRESS       address the HTTP port listens on (default 127.0.0.1; use SSH port
                            forwarding rather than 0.0.0.0: there is no authentication)
  --http-max-clients N      most HTTP connections at once, each WebSocket one (default 32); more
                            are answered 503 / TOO_MANY_CLIENTS and closed
  --studio-dir DIR          the studio's files (default: PREFIX/share/sim4cv/studio beside an
                            installed daemon, else the source tree's studio/)
  --udp-port N              UDP port; 0 picks any free port, -1 turns UDP off (default 0)
  --udp-datagram-bytes N    largest datagram the daemon sends; frames are chunked to fit
                            (default 65000 for loopback; 1472 for a 1500-byte MTU network)
  --udp-expiry-ms N         a UDP client's registration lapses after this much silence (default 5000)
  --shm-name NAME           serve shared memory to clients attaching through @sim4cv-shm/NAME (default: off)
  --shm-camera NAME         the camera the shared-memory ring carries (default uav)
  --shm-slots N             frame slots in the shared-memory ring (default 8)
  --shm-expiry-ms N         a shared-memory client silent this long is disconnected (default 5000)
  --shm-channels LIST       the pixel channels the shared-memory ring carries, separated by commas
                            (default rgb,depth,mask); fewer channels, less copying. The channels:
)" + ChannelHelp() +
         R"(  --conditions PRESET       weather and time of day of the RGB images: )" + conditions::Names() + R"(
                            (default clear_noon; docs/protocol.md, "Conditions"). Only RGB changes
                            (and albedo where rain wets the ground)
  --hour H                  local solar time in [0, 24] (default: the preset's own hour)
  --quality Q               full (sky, sun shadows, procedural materials) or fast (flat shading, the
                            cheapest; default full)
  --noise-read DN           sensor read noise of the full look: standard deviation in 8-bit levels,
                            0 .. 50 (default 0: off)
  --noise-shot K            sensor shot noise: variance K times the level, 0 .. 10 (default 0: off)
  --randomize SEED          domain randomisation: draw the conditions (preset, hour, exposure, a
                            colour jitter per object) from SEED, reproducibly (default 0: off)
  --randomize-every N       with --randomize, new conditions every N frames (default 0: once per
                            episode, i.e. at start, Reset and LoadMap)
Camera effects (docs/protocol.md, "Camera effects"; all off by default, a lens distorts every channel):
)" + EffectsHelp() +
         R"(  --log-level LEVEL         debug, info, warning or error (default info); log lines go to stderr
  --log FILE                record every frame (poses, tracker and ground-truth boxes, car controls)
                            to the run log FILE (docs/logs.md; extension .s4log by convention)
  --log-label TEXT          what the run is, e.g. the tracker's name, for the log's header (default:
                            the scene name)
  --logs-dir DIR            where clients' StartLog writes run logs (the studio's "start log");
                            default: none, StartLog is refused
  --log-max-bytes N         a run log (--log or StartLog) is closed once its file reaches N bytes
                            (default 2147483648; 1024 ... 2^50)
  --log-max-seconds S       ... or once its records span S simulated seconds (default 21600: six
                            hours; 1 ... 31536000)
  --replay FILE             the car and the UAV follow the poses of the run log FILE frame by frame
                            instead of physics, then hold the last pose; same scene and --frame-hz
  --replay-only IDS         with --replay, only these entities (e.g. 1: the target car) follow the
                            log; the others fly and drive by physics around them (default: all)
  --help                    this text

When ready it prints one line on stdout, e.g. `sim4cvd listening tcp=PORT udp=PORT shm=/NAME http=PORT`
(a field per transport that is on).
SIGINT or SIGTERM end it cleanly.
)";
}

// An installed daemon (cmake --install, the .deb) is PREFIX/bin/sim4cvd with its data in
// PREFIX/share/sim4cv/NAME; one run from a build folder has none there and uses the source
// tree it was built from. The installed copy wins, so a .deb's daemon never reads a source tree.
static std::string DataDir(const char* name, const char* source_tree_dir) {
  std::error_code error;
  const std::filesystem::path binary = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) return source_tree_dir;
  const std::filesystem::path installed = binary.parent_path().parent_path() / "share/sim4cv" / name;
  return std::filesystem::is_directory(installed, error) ? installed.string() : source_tree_dir;
}

std::string DefaultMapsDir() { return DataDir("scenes", SIM4CV_DEFAULT_MAPS_DIR); }

std::string DefaultStudioDir() { return DataDir("studio", SIM4CV_DEFAULT_STUDIO_DIR); }

std::optional<Config> ParseFlags(const std::vector<std::string>& args, std::string& help_text) {
  Config config;
  std::optional<double> hour;  // --hour, applied after --conditions wherever it stands
  using Setter = std::function<void(const std::string& flag, const std::string& value)>;
  std::map<std::string, Setter> setters = {
      {"--scene", [&](auto&, auto& v) { config.scene_file = v; }},
      {"--map", [&](auto&, auto& v) { config.map_file = v; }},
      {"--route", [&](auto&, auto& v) { config.route = v; }},
      {"--maps-dir", [&](auto&, auto& v) { config.maps_dir = v; }},
      {"--token-file", [&](auto&, auto& v) { config.token_file = v; }},
      {"--traffic-cars", [&](auto& f, auto& v) { config.traffic.moving_cars = ParseNumber<int>(f, v, 0, 500); }},
      {"--traffic-parked", [&](auto& f, auto& v) { config.traffic.parked_cars = ParseNumber<int>(f, v, 0, 2000); }},
      {"--traffic-pedestrians",
       [&](auto& f, auto& v) { config.traffic.pedestrians = ParseNumber<int>(f, v, 0, 2000); }},
      {"--traffic-lights",
       [&](auto& f, auto& v) {
         SIM4CV_THROW_UNLESS(v == "on" || v == "off", f << " is '" << v << "'; use on or off");
         config.traffic.traffic_lights = v == "on";
       }},
      {"--traffic-green", [&](auto& f, auto& v) { config.traffic.green_s = ParseNumber<double>(f, v, 0.1, 600); }},
      {"--traffic-yellow", [&](auto& f, auto& v) { config.traffic.yellow_s = ParseNumber<double>(f, v, 0, 60); }},
      {"--traffic-all-red", [&](auto& f, auto& v) { config.traffic.all_red_s = ParseNumber<double>(f, v, 0, 60); }},
      {"--traffic-seed",
       [&](auto& f, auto& v) {
         config.traffic.seed = ParseNumber<uint64_t>(f, v, 0, UINT64_MAX);
         config.traffic_seed_set = true;
       }},
      {"--car-speed", [&](auto& f, auto& v) { config.car_speed = ParseNumber<float>(f, v, 0.1f, 40.0f); }},
      {"--seed", [&](auto& f, auto& v) { config.seed = ParseNumber<uint64_t>(f, v, 0, UINT64_MAX); }},
      {"--bind", [&](auto&, auto& v) { config.bind_address = v; }},
      {"--tcp-port", [&](auto& f, auto& v) { config.tcp_port = ParseNumber<uint16_t>(f, v, 0, 65535); }},
      {"--physics-hz", [&](auto& f, auto& v) { config.physics_hz = ParseNumber<double>(f, v, 1, 100000); }},
      {"--frame-hz", [&](auto& f, auto& v) { config.frame_hz = ParseNumber<double>(f, v, 0.1, 1000); }},
      {"--width", [&](auto& f, auto& v) { config.width = ParseNumber<uint32_t>(f, v, 16, 4096); }},
      {"--height", [&](auto& f, auto& v) { config.height = ParseNumber<uint32_t>(f, v, 16, 4096); }},
      {"--mode",
       [&](auto& f, auto& v) {
         SIM4CV_THROW_UNLESS(v == "lockstep" || v == "realtime", f << " is '" << v << "'; use lockstep or realtime");
         config.mode = v == "lockstep" ? proto::SIM_MODE_LOCKSTEP : proto::SIM_MODE_REALTIME;
       }},
      {"--max-message-bytes",
       [&](auto& f, auto& v) { config.max_message_bytes = ParseNumber<uint32_t>(f, v, 16, 1u << 30); }},
      {"--max-clients", [&](auto& f, auto& v) { config.max_clients = ParseNumber<uint32_t>(f, v, 1, 100000); }},
      {"--tcp-send-buffer",
       [&](auto& f, auto& v) { config.tcp_send_buffer_bytes = ParseNumber<uint32_t>(f, v, 0, 1u << 30); }},
      {"--handshake-timeout-ms",
       [&](auto& f, auto& v) { config.handshake_timeout_ms = ParseNumber<uint32_t>(f, v, 0, 86400000); }},
      {"--message-timeout-ms",
       [&](auto& f, auto& v) { config.message_timeout_ms = ParseNumber<uint32_t>(f, v, 0, 86400000); }},
      {"--idle-timeout-ms",
       [&](auto& f, auto& v) { config.idle_timeout_ms = ParseNumber<uint32_t>(f, v, 0, 86400000); }},
      {"--controls-timeout-ms",
       [&](auto& f, auto& v) { config.controls_timeout_ms = ParseNumber<uint32_t>(f, v, 0, 86400000); }},
      {"--http-port", [&](auto& f, auto& v) { config.http_port = ParseNumber<int32_t>(f, v, -1, 65535); }},
      {"--http-bind", [&](auto&, auto& v) { config.http_bind = v; }},
      {"--http-max-clients",
       [&](auto& f, auto& v) { config.http_max_clients = ParseNumber<uint32_t>(f, v, 1, 100000); }},
      {"--studio-dir", [&](auto&, auto& v) { config.studio_dir = v; }},
      {"--udp-port", [&](auto& f, auto& v) { config.udp_port = ParseNumber<int32_t>(f, v, -1, 65535); }},
      {"--udp-datagram-bytes",
       [&](auto& f, auto& v) { config.udp_datagram_bytes = ParseNumber<uint32_t>(f, v, 576, 65000); }},
      {"--udp-expiry-ms", [&](auto& f, auto& v) { config.udp_expiry_ms = ParseNumber<uint32_t>(f, v, 10, 3600000); }},
      {"--shm-name",
       [&](auto& f, auto& v) {
         SIM4CV_THROW_UNLESS(!v.empty() && v != "/" && v.size() < 200 && v.find('/', 1) == std::string::npos,
                             f << " '" << v << "' must be a short name without '/' after the first character");
         config.shm_name = v[0] == '/' ? v : "/" + v;
       }},
      {"--shm-camera", [&](auto&, auto& v) { config.shm_camera = v; }},
      {"--shm-slots", [&](auto& f, auto& v) { config.shm_slots = ParseNumber<uint32_t>(f, v, 2, 1024); }},
      {"--shm-expiry-ms", [&](auto& f, auto& v) { config.shm_expiry_ms = ParseNumber<uint32_t>(f, v, 10, 3600000); }},
      {"--shm-channels", [&](auto& f, auto& v) { config.shm_channel_mask = ParseChannelList(f, v); }},
      {"--log-level",
       [&](auto& f, auto& v) {
         SIM4CV_THROW_UNLESS(v == "debug" || v == "info" || v == "warning" || v == "error",
                             f << " is '" << v << "'; use debug, info, warning or error");
         config.log_level = v;
       }},
      {"--log", [&](auto&, auto& v) { config.log_file = v; }},
      {"--log-label", [&](auto&, auto& v) { config.log_label = v; }},
      {"--logs-dir", [&](auto&, auto& v) { config.logs_dir = v; }},
      {"--log-max-bytes",
       [&](auto& f, auto& v) { config.log_max_bytes = ParseNumber<uint64_t>(f, v, 1024, uint64_t{1} << 50); }},
      {"--log-max-seconds",
       [&](auto& f, auto& v) { config.log_max_seconds = ParseNumber<double>(f, v, 1, 31536000); }},
      {"--replay", [&](auto&, auto& v) { config.replay_file = v; }},
      {"--replay-only", [&](auto& f, auto& v) { config.replay_only = ParseIdList(f, v); }},
      {"--conditions",
       [&](auto& f, auto& v) {
         const auto preset = conditions::FindByName(v);
         SIM4CV_THROW_UNLESS(preset, f << " '" << v << "' is not a preset; use one of " << conditions::Names());
         config.conditions.preset = *preset;
       }},
      {"--hour",
       [&](auto& f, auto& v) { hour = ParseNumber<double>(f, v, conditions::kMinHour, conditions::kMaxHour); }},
      {"--noise-read",
       [&](auto& f, auto& v) {
         config.conditions.noise_read = ParseNumber<double>(f, v, 0, conditions::kMaxNoiseRead);
       }},
      {"--noise-shot",
       [&](auto& f, auto& v) {
         config.conditions.noise_shot = ParseNumber<double>(f, v, 0, conditions::kMaxNoiseShot);
       }},
      {"--randomize", [&](auto& f, auto& v) { config.randomize_seed = ParseNumber<uint64_t>(f, v, 0, UINT64_MAX); }},
      {"--randomize-every",
       [&](auto& f, auto& v) { config.randomize_every_frames = ParseNumber<uint32_t>(f, v, 0, 1000000000); }},
      {"--quality",
       [&](auto& f, auto& v) {
         const auto quality = conditions::FindQuality(v);
         SIM4CV_THROW_UNLESS(quality, f << " '" << v << "' is not a quality; use full or fast");
         config.conditions.quality = *quality;
       }},
  };
  for (const effects::EffectInfo& info : effects::kEffects) {
    setters.emplace("--" + std::string(info.flag), [&config, &info](auto& f, auto& v) {
      config.effects.*info.member = ParseNumber<double>(f, v, info.min, info.max);
    });
  }
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--help" || args[i] == "-h") {
      help_text = HelpText();
      return std::nullopt;
    }
    if (args[i] == "--no-auth") {  // the one flag without a value
      config.no_auth = true;
      continue;
    }
    const auto setter = setters.find(args[i]);
    SIM4CV_THROW_UNLESS(setter != setters.end(), "unknown flag '" << args[i] << "'; see sim4cvd --help");
    SIM4CV_THROW_UNLESS(i + 1 < args.size(), args[i] << " needs a value; see sim4cvd --help");
    setter->second(args[i], args[i + 1]);
    ++i;
  }
  SIM4CV_THROW_UNLESS(config.scene_file.empty() || config.map_file.empty(), "--scene and --map both given; pick one");
  SIM4CV_THROW_UNLESS(config.log_label.empty() || !config.log_file.empty(), "--log-label needs --log FILE");
  if (!config.traffic_seed_set) config.traffic.seed = config.seed;
  config.conditions.hour = hour.value_or(conditions::Info(config.conditions.preset).hour);
  const std::string effects_problem = effects::Check(config.effects, true);
  SIM4CV_THROW_UNLESS(effects_problem.empty(), effects_problem);
  SIM4CV_THROW_UNLESS(config.randomize_every_frames == 0 || config.randomize_seed != 0,
                      "--randomize-every needs --randomize SEED (a non-zero seed)");
  SIM4CV_THROW_UNLESS(config.replay_only.empty() || !config.replay_file.empty(),
                      "--replay-only needs --replay FILE: it says which entities follow that log");
  // The writer truncates its file before replay could read it.
  SIM4CV_THROW_UNLESS(
      config.log_file.empty() || config.log_file != config.replay_file,
      "--log and --replay both name '" << config.log_file << "'; recording would erase the replayed log");
  SIM4CV_THROW_UNLESS(!config.no_auth || (IsLoopback(config.bind_address) &&
                                          (config.http_port < 0 || IsLoopback(config.http_bind))),
                      "--no-auth admits anyone who reaches the ports, so only with a loopback --bind and --http-bind "
                      "(127.0.0.1 or ::1); --bind is '"
                          << config.bind_address << "', --http-bind '" << config.http_bind
                          << "'. Give clients the token instead (docs/security.md)");
  SIM4CV_THROW_UNLESS(!config.no_auth || config.token_file.empty(), "--no-auth and --token-file both given; pick one");
  const double ratio = config.physics_hz / config.frame_hz;
  SIM4CV_THROW_UNLESS(
      std::abs(ratio - std::round(ratio)) < 1e-9 && ratio >= 1,
      "--physics-hz " << config.physics_hz << " must be a whole multiple of --frame-hz " << config.frame_hz);
  return config;
}

}  // namespace sim4cv::daemon
