// libsim4cv-client: one blocking client for sim4cvd over any of its
// transports, chosen by an address: tcp://HOST:PORT, udp://HOST:PORT or
// shm://NAME (docs/clients.md). It depends only on the protocol
// (protocol/), never on server code.
//
//   sim4cv::Client client;
//   client.Connect("shm:///sim4cv");   // or "tcp://127.0.0.1:5000", "udp://127.0.0.1:5001"
//   client.Subscribe("uav", {CHANNEL_RGB, CHANNEL_BOXES}, sim4cv::proto::DELIVERY_LOCKSTEP);
//   for (...) { const auto& frame = client.StepAndReceive(); ... }
//
// It also changes the world (docs/protocol.md, "Configuring the world"):
//   const uint32_t uav = client.Spawn(proto::ENTITY_KIND_UAV, "uav_b", 0, 0, 20);
//   client.AddCamera({.name = "uav_b_cam", .mounted_on = "uav_b", .pitch_down_deg = 45, .gimbal = true});
//   client.UavVelocity(uav, 2, 0, 0);
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

// Installed, protocol/ sits beside this file (PREFIX/include/sim4cv/protocol/) and
// sim4cv.pb.h in PREFIX/include; in the source tree both come from the include path.
#include "protocol/framing.h"
#include "sim4cv.pb.h"

namespace sim4cv {

class UdpClient;
class ShmClient;
namespace detail {
class Link;
}

// The daemon refused something: carries its code and message.
class ServerError : public std::runtime_error {
 public:
  ServerError(proto::ErrorCode code, const std::string& message, bool fatal, uint32_t request_id = 0);
  proto::ErrorCode code() const { return code_; }
  bool fatal() const { return fatal_; }
  // The Configure.request_id the Error answers; 0 for Errors about other messages.
  uint32_t request_id() const { return request_id_; }

 private:
  proto::ErrorCode code_;
  bool fatal_;
  uint32_t request_id_;
};

// The connection failed, closed, timed out, or the peer broke the framing.
class ConnectionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A non-owning view of one channel's pixels inside a received Frame: rows of
// `stride` bytes, each pixel `components` values of type `element`.
struct ImageView {
  const uint8_t* data = nullptr;
  uint32_t width = 0;
  uint32_t height = 0;
  uint32_t stride = 0;
  proto::PixelFormat format = proto::PIXEL_FORMAT_UNSPECIFIED;
  proto::ElementType element = proto::ELEMENT_TYPE_UNSPECIFIED;
  uint32_t components = 0;
  // Pixel (x, y) as T (float for DEPTH/NORMALS/FLOW, uint16_t for MASK, uint8_t else).
  template <typename T>
  const T* at(uint32_t x, uint32_t y) const {
    return reinterpret_cast<const T*>(data + static_cast<std::size_t>(y) * stride) +
           static_cast<std::size_t>(x) * components;
  }
};

// The channel's pixels in `frame`, or nullopt if the frame does not carry it.
std::optional<ImageView> FindImage(const proto::Frame& frame, proto::Channel channel);

// A camera for Client::AddCamera (proto AddCamera; the daemon checks the ranges).
struct CameraSetup {
  std::string name{};          // unique; what Subscribe names
  std::string mounted_on{};    // an entity's name; empty: fixed in the world at (x, y, z)
  uint32_t width = 320;        // pixels, 16 .. 1920
  uint32_t height = 180;       // pixels, 16 .. 1080
  double fov_y_deg = 60;       // vertical field of view, 10 .. 150
  double pitch_down_deg = 0;   // below the horizon (gimbal) or the body's forward axis, -90 .. 90
  double yaw_deg = 0;          // fixed mounts: turned left of the body's forward axis (world-fixed: of east)
  bool gimbal = false;         // hold the pitch whatever the body's roll and pitch
  double x = 0, y = 0, z = 0;  // mount point in the body frame (x forward, y left, z up), metres
};

class Client {
 public:
  using Duration = std::chrono::milliseconds;

  Client();
  ~Client();
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  // Connects to the daemon at `address` (tcp://HOST:PORT, udp://HOST:PORT
  // or shm://NAME, NAME as given to --shm-name), sends Hello and waits for
  // Welcome, all within `timeout`. Throws std::invalid_argument for an
  // address of another form, ServerError if the daemon refuses (e.g.
  // VERSION_MISMATCH), ConnectionError (ShmError for shared memory) naming
  // the address if nothing answers there.
  void Connect(const std::string& address, const std::string& client_name = "cpp-client",
               Duration timeout = Duration(5000), uint32_t protocol_version = 0 /* 0: this build's */);
  // The same as Connect("tcp://HOST:PORT", ...).
  void Connect(const std::string& host, uint16_t port, const std::string& client_name = "cpp-client",
               Duration timeout = Duration(5000), uint32_t protocol_version = 0 /* 0: this build's */);
  // Connects over TCP without the handshake (for tests that misbehave on purpose).
  void ConnectRaw(const std::string& host, uint16_t port, Duration timeout = Duration(5000));
  bool connected() const;
  // The address connected to ("" before the first Connect).
  const std::string& address() const { return address_; }
  const proto::Welcome& welcome() const { return welcome_; }

  // The transport's own client, for its optional knobs (UDP retry interval
  // and counters; shared memory: zero-copy FrameViews of the ring), or
  // nullptr when connected over another transport.
  UdpClient* udp();
  ShmClient* shm();

  // Subscribes and waits for Subscribed. Throws ServerError on refusal,
  // ConnectionError on timeout. Frames of a previous subscription still
  // queued when Subscribed arrives are dropped. Over shared memory the
  // camera must be the ring's and the channels ones it carries.
  void Subscribe(const std::string& camera, const std::vector<proto::Channel>& channels, proto::Delivery delivery,
                 bool with_state = false, Duration timeout = Duration(5000));

  // Lockstep: asks for the next frame (over UDP not retried: if the frame is
  // lost, ReceiveFrame times out and the caller Steps again).
  void Step();
  // Waits for the next Frame. Returns false on timeout. Throws ServerError if
  // an Error arrives (or was queued by Configure) first. The frame stays
  // valid until the next receive. Over shared memory: the newest frame of
  // the ring not received yet, copied once into `frame`.
  bool ReceiveFrame(proto::Frame& frame, Duration timeout = Duration(10000));
  // Step() then ReceiveFrame(); throws ConnectionError on timeout.
  const proto::Frame& StepAndReceive(Duration timeout = Duration(10000));
  // Newest frame on request (subscribe with DELIVERY_ON_REQUEST): the newest
  // frame this client was not given yet (over shared memory: the ring's),
  // else the next one rendered; at most one frame period plus its transfer
  // old. Frames queued before are dropped as stale. Throws ConnectionError
  // on timeout.
  const proto::Frame& RequestFrame(Duration timeout = Duration(10000));

  void SendTrackerOutput(uint64_t frame_id, float x, float y, float width, float height, float confidence);
  void SendControls(uint32_t entity_id, float steering, float throttle, float brake);
  // Sends GetState and waits for State. Frames arriving meanwhile are kept
  // for the next ReceiveFrame. Over TCP and shared memory a State already
  // queued (the answer to a GetState sent through SendEnvelope) is returned
  // without a new request; over UDP it is stale and dropped. Throws
  // ConnectionError on timeout.
  proto::State GetState(Duration timeout = Duration(5000));
  // The daemon's counters (docs/protocol.md, "Counters").
  proto::Stats GetStats(Duration timeout = Duration(5000));

  // Configuring the world (docs/protocol.md, "Configuring the world"): sends
  // `request` with the next request_id (overwriting the one given) and waits
  // for the answer carrying that id. Throws ServerError (request_id() set)
  // if the daemon refuses it, ConnectionError on timeout. Envelopes arriving
  // meanwhile are queued: Frames for ReceiveFrame, and Errors that are not
  // this request's answer (e.g. UNKNOWN_CAMERA for a subscription whose
  // camera was just removed) for the next call that waits, which throws them.
  // Over UDP the request is retried with its request_id, which the daemon
  // carries out once; over shared memory it goes through a TCP connection
  // of its own to the same daemon (the rings' messages are too small).
  proto::Configured Configure(proto::Configure request, Duration timeout = Duration(30000));
  // Convenience wrappers: one request each, answered with the world after
  // the change. Same exceptions as Configure.
  //
  // Replaces the world with a shipped map, e.g. "tracking/hard_urban" (route
  // "": the map's first closed route; car_speed 0: the daemon's --car-speed;
  // traffic unset: the daemon's --traffic-* flags).
  proto::WorldInfo LoadMapByName(const std::string& name, const std::string& route = "", float car_speed = 0,
                                 const std::optional<proto::TrafficSettings>& traffic = std::nullopt);
  // The same with the text of a map file (docs/maps.md).
  proto::WorldInfo LoadMapText(const std::string& text, const std::string& route = "", float car_speed = 0,
                               const std::optional<proto::TrafficSettings>& traffic = std::nullopt);
  // Adds a car (at rest, brake on; z ignored) or a UAV (hovering; z above the
  // ground, more than 0.5 m). name "": "car_<id>" / "uav_<id>". Returns the new id.
  uint32_t Spawn(proto::EntityKind kind, const std::string& name, double x, double y, double z, double yaw_deg = 0,
                 bool snap_to_lane = false);
  proto::WorldInfo Remove(uint32_t entity_id);
  // A car drives one of the map's routes (WorldInfo.routes), or the given
  // lane-centre points, at `speed` m/s (0 .. 40).
  proto::WorldInfo SetRoute(uint32_t entity_id, const std::string& route_name, float speed);
  proto::WorldInfo SetWaypoints(uint32_t entity_id, const std::vector<std::array<double, 2>>& points, bool closed,
                                float speed);
  // Keeps the car's route, changes its speed; 0 stops it.
  proto::WorldInfo SetSpeed(uint32_t entity_id, float speed);
  // UAV orders: film `target_id` from behind and above (altitude/pitch 0:
  // 15 m / 60 deg), hold a point, or fly a world-frame velocity.
  proto::WorldInfo UavFollow(uint32_t uav_id, uint32_t target_id, double altitude = 0, double pitch_down_deg = 0);
  proto::WorldInfo UavHold(uint32_t uav_id, double x, double y, double z, double yaw_deg = 0);
  proto::WorldInfo UavVelocity(uint32_t uav_id, double vx, double vy, double vz, double yaw_rate_deg = 0);
  // Tracking in the loop: the UAV steers by the boxes its camera `camera`'s
  // trackers send (SendTrackerOutput of clients subscribed to it): it holds
  // station `distance` metres behind where the newest box puts the target
  // (0: where the camera centre looks), at `altitude` (0: the current one).
  // docs/tracking.md, "The servo".
  proto::WorldInfo UavTrack(uint32_t uav_id, const std::string& camera, double distance = 0, double altitude = 0);
  proto::WorldInfo AddCamera(const CameraSetup& camera);
  // Moves a camera fixed in the world (AddCamera without mounted_on) from
  // the next frame on: position (m), heading (degrees from east,
  // counter-clockwise) and pitch below the horizon.
  proto::WorldInfo SetCameraPose(const std::string& camera, double x, double y, double z, double yaw_deg,
                                 double pitch_down_deg = 0);
  // Removes a camera AddCamera added; its subscribers get an UNKNOWN_CAMERA Error.
  proto::WorldInfo RemoveCamera(const std::string& name);
  // Back to the loaded map's start: time 0, spawned entities and added cameras gone.
  proto::WorldInfo Reset();
  proto::WorldInfo GetWorld();
  // Weather and time of day of the RGB images from the next frame on:
  // preset "clear_noon", "clear_morning", "overcast", "fog", "dusk", "night"
  // or "rain" ("": keep), hour in [0, 24] (unset: the preset's), quality
  // "full" or "fast" ("": keep). Other channels never change with them.
  proto::WorldInfo SetConditions(const std::string& preset, std::optional<double> hour = std::nullopt,
                                 const std::string& quality = "");
  // Camera effects (lens distortion, motion blur, anti-aliasing, exposure,
  // white balance, JPEG; docs/protocol.md "Camera effects"): the fields set
  // in `effects` change, the others keep their value; WorldInfo.effects
  // says what is in force. A lens distorts every channel and the boxes.
  proto::WorldInfo SetEffects(const proto::CameraEffects& effects);
  // Map scenes only: the nearest lane point to (x, y) (only lanes within 90
  // degrees of `heading_deg` if given), and `count` points every `step`
  // metres ahead of it.
  proto::RoadQueryResult QueryRoad(double x, double y, uint32_t count = 0, double step = 0,
                                   std::optional<double> heading_deg = std::nullopt);

  // Low level: one envelope out (TCP: with its length prefix).
  void SendEnvelope(const proto::Envelope& envelope);
  // Low level: raw bytes exactly as given (tests use it to send garbage).
  void SendRaw(const void* data, std::size_t size);
  // Low level: next envelope of any kind (queued ones first). False on timeout.
  // An Error is returned like any other envelope, not thrown.
  bool ReceiveEnvelope(proto::Envelope& envelope, Duration timeout);

  // TCP: envelopes the server announces as larger than this are refused with
  // a ConnectionError (default: wire::kDefaultMaxMessageBytes, 64 MiB:
  // frames can be tens of MB).
  void set_max_message_bytes(uint32_t bytes);
  uint32_t max_message_bytes() const { return max_message_bytes_; }

  // Idempotent. Drops queued envelopes and any partly read one.
  void Close();

 private:
  using Deadline = std::chrono::steady_clock::time_point;

  // What a wait stops at: the envelope it wants, and whether other Errors
  // interrupt it (fatal ones always do) or queue for the next wait.
  struct Awaited {
    std::function<bool(const proto::Envelope&)> wanted;
    bool errors_interrupt = true;
    bool frame = false;  // a frame is wanted (shared memory reads the ring only then)
  };
  // Sends `request` over `link` (again every retry interval of a lossy
  // link) until what `awaited` wants arrives; see ReceiveMatching.
  bool Request(detail::Link& link, const proto::Envelope& request, const Awaited& awaited, proto::Envelope& out,
               Deadline deadline);
  // Reads until an envelope of `kind` arrives; others queue. An Error (one
  // queued before the envelope wanted, or read while waiting) is thrown.
  bool ReceiveKind(proto::Envelope::KindCase kind, proto::Envelope& out, Deadline deadline);
  // Reads from `link` until what `awaited` wants arrives (queued ones
  // first); others queue.
  bool ReceiveMatching(detail::Link& link, const Awaited& awaited, proto::Envelope& out, Deadline deadline);
  // Configure, answered with the world after the change.
  proto::WorldInfo ConfigureWorld(proto::Configure request);
  [[noreturn]] void ThrowServerError(const proto::Error& error);  // closes first if fatal
  detail::Link& link() const;                                     // throws ConnectionError unless connected

  std::unique_ptr<detail::Link> link_;
  std::string address_;
  uint32_t max_message_bytes_ = wire::kDefaultMaxMessageBytes;
  proto::Welcome welcome_;
  uint32_t last_request_id_ = 0;
  proto::Envelope scratch_;
  proto::Frame frame_;
  std::deque<proto::Envelope> pending_;
};

}  // namespace sim4cv
