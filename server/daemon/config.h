// Every setting of the daemon, with its default, parsed from the command line.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "protocol/channels.h"
#include "protocol/conditions.h"
#include "protocol/effects.h"
#include "protocol/shm_layout.h"
#include "server/common/limits.h"
#include "server/sim/traffic/traffic_config.h"
#include "server/transport/shm/shm_region.h"
#include "sim4cv.pb.h"

namespace sim4cv::daemon {

// The shipped maps: PREFIX/share/sim4cv/scenes beside an installed daemon's
// bin/, else the source tree's scenes/.
std::string DefaultMapsDir();

// The studio's files: PREFIX/share/sim4cv/studio beside an installed daemon's
// bin/, else the source tree's studio/.
std::string DefaultStudioDir();

struct Config {
  std::string scene_file;                   // empty: the embedded default scene
  std::string map_file;                     // a tile map (docs/maps.md) instead of a scene file
  std::string route;                        // the map route the target car drives; empty: the first closed one
  float car_speed = 6.0f;                   // m/s, the target car's set speed on a map
  std::string maps_dir = DefaultMapsDir();  // where LoadMap finds shipped maps by name
  // Traffic on map scenes (docs/maps.md, "Traffic"); applies to every map
  // loaded, at start or by a client's LoadMap. Its seed is --traffic-seed,
  // else --seed.
  traffic::TrafficConfig traffic;
  bool traffic_seed_set = false;
  // Weather, time of day and quality of the RGB images (--conditions,
  // --hour, --quality); clients change them with Configure.set_conditions.
  conditions::Conditions conditions;
  // Camera effects (--antialias, --lens-k1, ...; protocol/effects.h); clients
  // change them with Configure.set_effects.
  effects::CameraEffects effects;
  // Domain randomisation (--randomize SEED, --randomize-every N): 0 = off.
  uint64_t randomize_seed = 0;
  uint32_t randomize_every_frames = 0;  // 0: once per episode
  uint64_t seed = 1;
  std::string bind_address = "127.0.0.1";
  uint16_t tcp_port = 0;
  // Access control (docs/security.md): Hello must carry the daemon's token,
  // generated at start or read from token_file; no_auth (loopback binds
  // only) turns it off.
  std::string token_file;
  bool no_auth = false;
  double physics_hz = 240.0;
  double frame_hz = 30.0;
  uint32_t width = 320;
  uint32_t height = 180;
  proto::SimMode mode = proto::SIM_MODE_LOCKSTEP;
  uint32_t max_message_bytes = limits::kDefaultMaxMessageBytes;
  uint32_t max_clients = 64;
  uint32_t tcp_send_buffer_bytes = 256u << 10;
  // TCP connection timeouts (docs/protocol.md, section 2); 0 turns one off.
  uint32_t handshake_timeout_ms = limits::kDefaultHandshakeTimeoutMs;
  uint32_t message_timeout_ms = limits::kDefaultMessageTimeoutMs;
  uint32_t idle_timeout_ms = limits::kDefaultIdleTimeoutMs;
  // A car driven by Controls that gets none for this long (simulation time)
  // brakes to a stop and is free for another client; 0 turns it off.
  uint32_t controls_timeout_ms = 1000;
  int32_t udp_port = 0;  // -1: no UDP transport
  // The studio (docs/studio.md): its pages and a WebSocket transport on one
  // HTTP port; -1: off. Bound to loopback unless --http-bind says otherwise:
  // anyone who reaches the port can drive the simulation.
  int32_t http_port = -1;
  std::string http_bind = "127.0.0.1";
  uint32_t http_max_clients = 32;               // HTTP connections at once, WebSockets included
  std::string studio_dir = DefaultStudioDir();  // the page's files (studio/)
  uint32_t udp_datagram_bytes = 65000;
  uint32_t udp_expiry_ms = 5000;
  std::string shm_name;  // empty: no shared-memory transport
  std::string shm_camera = "uav";
  uint32_t shm_slots = 8;
  uint32_t shm_expiry_ms = 5000;  // a silent shared-memory client is disconnected after this
  // --shm-channels: bit (1 << proto::Channel) per pixel channel the ring carries.
  // The channels the shm ring carries (--shm-channels).
  channels::ChannelSet shm_channel_mask = transport::kShmDefaultChannels;
  std::string log_level = "info";
  // Run logs (docs/logs.md): record every frame to log_file; replay_file makes
  // the car and the UAV follow a recorded log's poses instead of physics.
  std::string log_file;               // empty: no run log
  std::string log_label;              // the log header's label; empty: the scene name
  std::string logs_dir;               // where StartLog writes; empty: StartLog is refused
  // Every run log (--log's and StartLog's) is closed once its file reaches
  // this size or its records span this many simulated seconds, so a log
  // nobody stops (~138 KB/s of the default scene) cannot fill the disk.
  uint64_t log_max_bytes = uint64_t{2} << 30;
  double log_max_seconds = 6 * 3600.0;
  std::string replay_file;            // empty: simulate
  std::vector<uint32_t> replay_only;  // entity ids that follow the log; empty: all (physics is not stepped)

  // Physics steps per frame; physics_hz must be a whole multiple of frame_hz.
  uint32_t substeps_per_frame() const;
};

// Parses argv (without the program name). Returns nullopt and fills
// `help_text` for --help (then exit 0);
// or throws std::invalid_argument naming the bad flag or value.
std::optional<Config> ParseFlags(const std::vector<std::string>& args, std::string& help_text);

// The --help text.
std::string HelpText();

}  // namespace sim4cv::daemon
