// Validated requests that transports post to the sim thread. Transports have
// already checked every field against the immutable scene, so the sim thread
// applies them without further checks.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <variant>

#include "protocol/channels.h"
#include "server/session/client_link.h"
#include "sim4cv.pb.h"

namespace sim4cv::session {

using ClientId = uint32_t;

class MailboxGate;  // frame_mailbox.h

// Ids unique across all transports of the process, from 1.
inline ClientId NewClientId() {
  static std::atomic<ClientId> next{1};
  return next.fetch_add(1, std::memory_order_relaxed);
}

struct SubscribeCommand {
  uint32_t camera_index = 0;
  proto::Delivery delivery = proto::DELIVERY_NEWEST;
  channels::ChannelSet channels = 0;                  // what the frames must carry
  std::shared_ptr<ClientLink> link;                   // where frames go
  std::shared_ptr<const MailboxGate> gate = nullptr;  // lockstep: whether the client's mailbox is full
  int64_t min_interval_ns = 0;                        // Subscribe.max_fps as a period; 0: every frame
};

struct StepCommand {};

// Which car the controls are for is checked by the sim thread, which knows
// the current entities; it answers a wrong id through `link`.
struct ControlsCommand {
  uint32_t entity_id = 0;
  float steering = 0, throttle = 0, brake = 0;
  std::shared_ptr<ClientLink> link;
};

// One Configure's way back to its client, on every transport: it forwards
// the answer to the client's own link, and first gives back the client's slot
// for outstanding Configures (limits::kMaxOutstandingConfigures), so a client
// that waits for each answer may always send its next request. A request
// dropped unanswered (the daemon stops) gives its slot back too.
class ConfigureReplyLink final : public ClientLink {
 public:
  // `outstanding` was already counted up for this request.
  ConfigureReplyLink(std::shared_ptr<ClientLink> link, std::shared_ptr<std::atomic<uint32_t>> outstanding)
      : link_(std::move(link)), outstanding_(std::move(outstanding)) {}
  ~ConfigureReplyLink() override { GiveBack(); }
  ConfigureReplyLink(const ConfigureReplyLink&) = delete;
  ConfigureReplyLink& operator=(const ConfigureReplyLink&) = delete;

  void OfferFrame(const FrameRef& frame) override {
    if (link_) link_->OfferFrame(frame);
  }
  void OfferReply(proto::Envelope reply) override {
    GiveBack();
    if (link_) link_->OfferReply(std::move(reply));
  }

 private:
  void GiveBack() {
    if (outstanding_) outstanding_->fetch_sub(1, std::memory_order_acq_rel);
    outstanding_.reset();
  }

  std::shared_ptr<ClientLink> link_;
  std::shared_ptr<std::atomic<uint32_t>> outstanding_;
};

// A Configure whose fields are valid on their own (finite, in range); the
// sim thread checks it against the world, carries it out between frames and
// answers through `link` (Configured or an Error), a ConfigureReplyLink.
struct ConfigureCommand {
  proto::Configure request;
  std::shared_ptr<ClientLink> link;
};

// A tracker's box, finite and of positive size; the sim thread checks it
// against the client's camera and frames and answers an Error through
// `link` if it refuses it.
struct TrackerOutputCommand {
  uint64_t frame_id = 0;
  float x = 0, y = 0, width = 0, height = 0, confidence = 0;
  std::shared_ptr<ClientLink> link;
};

// The client is gone: forget its subscription and step credits.
struct DisconnectCommand {};

struct Command {
  ClientId client = 0;
  std::variant<SubscribeCommand, StepCommand, ControlsCommand, TrackerOutputCommand, ConfigureCommand,
               DisconnectCommand>
      body;
};

}  // namespace sim4cv::session
