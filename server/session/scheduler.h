// Who is subscribed to what, and when a lockstep simulation may advance.
// Lives on the sim thread only.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "server/session/command.h"
#include "server/session/frame_mailbox.h"

namespace sim4cv::session {

class Scheduler {
 public:
  // `gate` (may be null) tells whether the client's lockstep mailbox is full.
  // `min_interval_ns` (Subscribe.max_fps as a period; newest and on-request
  // only): the subscriber wants a frame at most that often, by the clock
  // BeginFrame gives; 0: every frame.
  void Subscribe(ClientId client, uint32_t camera_index, proto::Delivery delivery, channels::ChannelSet channels,
                 std::shared_ptr<ClientLink> link, std::shared_ptr<const MailboxGate> gate = nullptr,
                 int64_t min_interval_ns = 0);
  // One Step from a lockstep subscriber: one credit. Others are ignored (the
  // transport has already refused them).
  void AddStep(ClientId client);
  // Forgets the client (disconnect), so nobody waits for it.
  void Remove(ClientId client);

  // Lockstep rule: at least one lockstep subscriber, and every one of them
  // holds a credit and has room in its mailbox (fewer than
  // limits::kLockstepFramesQueued frames waiting): a client that does not
  // read holds the simulation back, as one that does not Step does, instead
  // of making the daemon render and keep frames for it.
  bool LockstepReady() const;
  // Takes one credit from every lockstep subscriber.
  void ConsumeSteps();

  // The wall clock for this frame's rate-capped subscriptions: whether each
  // is due (ChannelsWanted leaves out those that are not, Deliver skips
  // them). Only what such a subscriber is sent depends on it, never what
  // any frame holds or when a lockstep simulation steps.
  void BeginFrame(std::chrono::steady_clock::time_point now) {
    now_ns_ = std::chrono::duration_cast<std::chrono::nanoseconds>(now.time_since_epoch()).count();
  }

  // Whether anyone wants frames of this camera.
  bool CameraWanted(uint32_t camera_index) const { return ChannelsWanted(camera_index) != 0; }
  // What the camera's frames must hold: the union of its live subscribers'
  // channels (0: none, nothing to render).
  channels::ChannelSet ChannelsWanted(uint32_t camera_index) const;
  // What the camera's subscribers that send the Frame's own pixels
  // (ClientLink::SendsFramePixels) want, but `except`.
  channels::ChannelSet ChannelsSentFromFrame(uint32_t camera_index, const ClientLink* except) const;
  // The camera's subscribers, for the sim thread to ask which can take
  // pixels in place (ClientLink::PrepareTargets).
  template <typename Visit>
  void ForEachLink(uint32_t camera_index, Visit&& visit) const {
    for (const auto& s : subscriptions_) {
      if (s.camera_index == camera_index && s.link) visit(*s.link);
    }
  }
  // The camera `client` is subscribed to, if any.
  std::optional<uint32_t> CameraOf(ClientId client) const;
  // Hands `frame` to every subscriber of its camera, in client-id order; with
  // an observer, to the observer at once and to subscribers at ReleaseFrames.
  void Deliver(const FrameRef& frame);

  // The run logger sees every rendered frame (it subscribes to no camera, so
  // it neither makes one wanted nor steps). While it is set, subscribers get
  // a simulation frame's camera frames only at ReleaseFrames(), after the
  // frame's log record is written: no client can hold a frame that a crash
  // could leave out of the log. nullptr removes it.
  void SetObserver(ClientLink* observer) { observer_ = observer; }
  void ReleaseFrames();

  std::size_t subscriber_count() const { return subscriptions_.size(); }

  // A camera that stops existing (its entity or itself removed) is dead: its
  // subscribers get no frames and no longer hold lockstep back, until it
  // lives again (Reset or LoadMap bring the scene's cameras back). Returns
  // the links of its subscribers, to tell them.
  std::vector<std::shared_ptr<ClientLink>> SetCameraDead(uint32_t camera_index, bool dead);
  // Forgets every subscription to cameras at or above `camera_index` (a new
  // scene reuses those indices); returns their links.
  std::vector<std::shared_ptr<ClientLink>> DropCamerasFrom(uint32_t camera_index);

 private:
  struct Subscription {
    ClientId client = 0;
    uint32_t camera_index = 0;
    proto::Delivery delivery = proto::DELIVERY_NEWEST;
    channels::ChannelSet channels = 0;
    uint64_t step_credits = 0;
    std::shared_ptr<ClientLink> link;
    std::shared_ptr<const MailboxGate> gate;
    int64_t min_interval_ns = 0;  // 0: every frame
    int64_t next_due_ns = 0;      // rate-capped: no frame before this
  };
  bool Due(const Subscription& s) const { return s.min_interval_ns == 0 || now_ns_ >= s.next_due_ns; }
  Subscription* Find(ClientId client);
  void OfferToSubscribers(const FrameRef& frame);
  bool Dead(uint32_t camera_index) const { return camera_index < dead_cameras_.size() && dead_cameras_[camera_index]; }

  std::vector<Subscription> subscriptions_;  // ordered by client id
  ClientLink* observer_ = nullptr;
  std::vector<FrameRef> held_;      // frames awaiting ReleaseFrames; keeps its capacity
  std::vector<bool> dead_cameras_;  // by camera index; missing: alive
  int64_t now_ns_ = 0;              // BeginFrame's
};

}  // namespace sim4cv::session
