// sim4cv::ShmClient: frames from sim4cvd's shared-memory ring (--shm-name)
// read in place, and requests (Hello, Subscribe, Step, TrackerOutput,
// Controls, GetState) through this client's own request ring. Open attaches
// through the daemon's Unix socket, which hands over the frame object (mapped
// read-only) and this client's area (requests and responses). Layout and
// rules: protocol/shm_layout.h and docs/protocol.md section 13. Depends on
// the protocol only, never on server code.
//
//   sim4cv::ShmClient shm;
//   shm.Open("/sim4cv");
//   shm.Hello("tracker");
//   shm.Subscribe(sim4cv::proto::DELIVERY_LOCKSTEP);
//   uint64_t last = 0;
//   for (...) {
//     shm.Step();
//     shm.WaitForFrame(last, std::chrono::milliseconds(1000));
//     sim4cv::FrameView view;
//     shm.AcquireNewest(view);           // zero-copy: pointers into the ring
//     ... use view.image(CHANNEL_RGB), view.boxes() ...
//     (a ring started with --shm-channels carries only those: view.has(c))
//     if (view.stale()) { /* the daemon overwrote it meanwhile: discard */ }
//     last = view.frame_id();
//     shm.SendTrackerOutput(last, x, y, w, h, confidence);
//   }
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "protocol/shm_sync.h"
#include "sim4cv.pb.h"
#include "sim4cv/client.h"  // ImageView, ServerError, ConnectionError

namespace sim4cv {

// The object is missing or is not a sim4cv ring this client can read.
class ShmError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

using ShmBox = shm::ShmBox;
using ShmEntityPose = shm::ShmEntityPose;

// A frame in place in the ring. The metadata (ids, sizes, boxes, poses) is
// copied into the view when it is acquired and is consistent; the pixels stay
// in shared memory and are valid until the daemon reuses the slot, which it
// does without waiting (slot_count - 1 frames later). Check stale() after
// using the pixels: if true, they may have changed while you read them.
// A view holds nothing in shared memory: a reader that crashes blocks no one.
class FrameView {
 public:
  bool valid() const { return slot_ != nullptr; }
  uint64_t frame_id() const { return header_.frame_id; }
  double sim_time() const { return header_.sim_time; }
  int64_t render_end_mono_ns() const { return header_.render_end_mono_ns; }
  uint32_t width() const { return header_.width; }
  uint32_t height() const { return header_.height; }
  // The ring publication this frame was written as (consecutive frames: +1).
  uint64_t publication() const { return header_.publication; }
  // True if the frame holds this pixel channel (RGB, DEPTH, MASK): the ring
  // carries only the channels of the daemon's --shm-channels.
  bool has(proto::Channel channel) const;
  // RGB, DEPTH or MASK pixels in place; nullopt if !has(channel).
  std::optional<ImageView> image(proto::Channel channel) const;
  std::span<const ShmBox> boxes() const { return {header_.boxes, header_.box_count}; }
  // Visible labelled objects; more than boxes().size() if the slot's box array was full.
  uint32_t box_total() const { return header_.box_total; }
  std::span<const ShmEntityPose> entities() const { return {header_.entities, header_.entity_count}; }

  // True once the daemon has begun overwriting this view's slot.
  bool stale() const;
  // Throws ShmError if stale(): the pixels read since acquiring may be torn.
  void Validate() const;
  // Drops the pointers. Nothing in shared memory needs releasing.
  void Release();

 private:
  friend class ShmClient;
  const uint8_t* slot_ = nullptr;
  uint64_t sequence_ = 0;
  shm::ShmFrameHeader header_{};
};

// A frame copied out of the ring.
struct OwnedFrame {
  uint64_t frame_id = 0;
  uint64_t publication = 0;
  double sim_time = 0;
  int64_t render_end_mono_ns = 0;
  uint32_t width = 0, height = 0;
  // The pixel channels the ring carries (bit 1 << proto::Channel); the
  // plane of a channel it does not carry is empty.
  uint32_t channel_mask = 0;
  // Plane i: channel channels::kPixelChannels[i], height * width pixels.
  std::array<std::vector<uint8_t>, channels::kPixelChannelCount> planes;
  bool has(proto::Channel channel) const;
  // A view of the copied pixels; nullopt if !has(channel).
  std::optional<ImageView> image(proto::Channel channel) const;
  std::vector<ShmBox> boxes;
  uint32_t box_total = 0;
  std::vector<ShmEntityPose> entities;
};

class ShmClient {
 public:
  using Duration = std::chrono::milliseconds;

  ShmClient() = default;
  ~ShmClient();
  ShmClient(const ShmClient&) = delete;
  ShmClient& operator=(const ShmClient&) = delete;

  // Attaches to the daemon serving --shm-name `name` ("/name" or "name"):
  // connects to its Unix socket, receives the frame object and this
  // client's area, maps and checks them. Throws ShmError if no daemon
  // serves the name, it refuses (the message says why), or it speaks
  // another layout version (the message names both).
  void Open(const std::string& name);
  // Low level: maps only a frame object from its descriptor (a reader that
  // got it some other way; tests). Requests need Open.
  void OpenFrames(int frames_fd);
  void Close();
  bool is_open() const { return frames_ != nullptr; }
  const shm::ShmHeader& header() const { return *reinterpret_cast<const shm::ShmHeader*>(frames_); }
  std::string camera() const;
  // Whether the ring's frames hold this pixel channel (the daemon's --shm-channels).
  bool carries(proto::Channel channel) const;

  // Frames. Newest published frame id (0: none yet).
  uint64_t newest_frame_id() const;
  // True once the daemon has stopped: no more frames or responses.
  bool closed() const;
  // Zero-copy view of the newest frame; false if none was published yet.
  bool AcquireNewest(FrameView& view) const;
  // Copies the newest frame, retrying torn reads; false if none yet.
  bool ReadNewest(OwnedFrame& frame) const;
  // Waits (futex, after a short spin) until a frame newer than
  // `after_frame_id` is published. False on timeout; throws ConnectionError
  // if the daemon stopped.
  bool WaitForFrame(uint64_t after_frame_id, Duration timeout) const;

  // How long WaitForFrame and response waits poll before sleeping in
  // FUTEX_WAIT. Default 0: the futex alone wakes within microseconds, and a
  // spin only burns a core that the daemon may need (docs/protocol.md 13.4).
  void set_spin(std::chrono::microseconds spin) { spin_ = spin; }

  // Requests through this client's request ring; replies come back through
  // its response ring. Hello and Subscribe wait for their answer and throw
  // ServerError if the daemon refuses; Step, SendTrackerOutput and
  // SendControls do not wait (a refusal arrives later, see ReceiveReply).
  // Hello attaches again if the daemon ended the attachment (13.7).
  proto::Welcome Hello(const std::string& client_name = "cpp-shm-client", Duration timeout = Duration(5000),
                       uint32_t protocol_version = 0 /* 0: this build's */);
  // Subscribes to the ring's camera (frames stay in the ring), with the
  // channels the ring carries and BOXES.
  void Subscribe(proto::Delivery delivery, Duration timeout = Duration(5000));
  // The same with these channels; one the ring does not carry gets a
  // ServerError (INVALID_ARGUMENT) naming it and --shm-channels.
  void Subscribe(proto::Delivery delivery, const std::vector<proto::Channel>& channels,
                 Duration timeout = Duration(5000));
  void Step();
  void SendTrackerOutput(uint64_t frame_id, float x, float y, float width, float height, float confidence);
  void SendControls(uint32_t entity_id, float steering, float throttle, float brake);
  proto::State GetState(Duration timeout = Duration(5000));

  // Low level: one Envelope into the request ring (at most
  // shm::kShmRequestDataBytes encoded; ShmError if larger).
  void SendEnvelope(const proto::Envelope& envelope);
  // Low level: raw bytes as one request (tests use it to send garbage).
  void SendRaw(const void* data, std::size_t size);
  // Low level: the next response of any kind (queued ones first); false on
  // timeout. Errors are returned, not thrown; ConnectionError once the
  // daemon ended the attachment and every response was read.
  bool ReceiveReply(proto::Envelope& reply, Duration timeout);
  // Responses the daemon wrote that were overwritten before this client read them.
  uint64_t responses_lost() const { return responses_lost_; }
  // True while attached (Open succeeded and the daemon has not ended it).
  bool attached() const;
  // Low level, for tests: this client's area (writable) and descriptors.
  uint8_t* area() const { return area_; }
  int socket_fd() const { return socket_; }
  int doorbell_fd() const { return doorbell_; }
  int frames_fd() const { return frames_fd_; }
  int area_fd() const { return area_fd_; }

 private:
  using Deadline = std::chrono::steady_clock::time_point;
  bool CopyNewest(OwnedFrame& frame) const;
  void RequireOpen() const;  // throws ShmError
  void Attach();             // connects and maps the area (and the frames, if not yet)
  void Detach();             // unmaps the area, closes the socket and doorbell
  void MapFrames(int fd, uint64_t bytes);
  bool TryReadResponse(proto::Envelope& reply);
  // Response `k`, `size` bytes, that the ring says is on the socket; false
  // (the response is lost) if the socket does not hold it.
  bool ReceiveLongResponse(uint64_t k, uint32_t size, proto::Envelope& reply);
  // After falling a lap behind: drops the socket messages of responses before
  // `k`, which the ring overwrote, so they no longer fill the socket.
  void DiscardLongResponsesBefore(uint64_t k);
  bool NextResponse(proto::Envelope& reply, Deadline deadline);  // from shared memory, not pending_
  bool ReceiveKind(proto::Envelope::KindCase kind, proto::Envelope& out, Deadline deadline);
  // Throws ConnectionError unless attached; `check_socket` also asks the
  // kernel whether the daemon's end of the socket is still open (a syscall).
  void RequireAttached(bool check_socket) const;
  bool attached(bool check_socket) const;

  // The frame object (read-only) and the geometry this client checked.
  uint8_t* frames_ = nullptr;
  shm::Geometry geometry_;
  int frames_fd_ = -1;
  std::string name_;
  // This client's area, socket and doorbell (while attached).
  uint8_t* area_ = nullptr;
  int area_fd_ = -1, socket_ = -1, doorbell_ = -1;
  uint64_t next_request_ = 0;   // own count of requests written
  uint64_t next_response_ = 0;  // next response to read
  uint64_t responses_lost_ = 0;
  std::chrono::microseconds spin_{0};
  std::deque<proto::Envelope> pending_;
  std::string scratch_;
  std::vector<uint8_t> long_response_;  // a socket message: at most kShmSocketResponse(Header)Bytes
};

}  // namespace sim4cv
