// Who is subscribed to what, and when a lockstep simulation may advance.
// Lives on the sim thread only.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "server/session/command.h"

namespace sim4cv::session {

class Scheduler {
 public:
  void Subscribe(ClientId client, uint32_t camera_index, proto::Delivery delivery, std::shared_ptr<ClientLink> link);
  // One Step from a lockstep subscriber: one credit. Others are ignored (the
  // transport has already refused them).
  void AddStep(ClientId client);
  // Forgets the client (disconnect), so nobody waits for it.
  void Remove(ClientId client);

  // Lockstep rule: at least one lockstep subscriber, and every one of them
  // holds a credit.
  bool LockstepReady() const;
  // Takes one credit from every lockstep subscriber.
  void ConsumeSteps();

  // Whether anyone wants frames of this camera.
  bool CameraWanted(uint32_t camera_index) const;
  // Hands `frame` to every subscriber of its camera, in client-id order.
  void Deliver(const FrameRef& frame) const;

  std::size_t subscriber_count() const { return subscriptions_.size(); }

 private:
  struct Subscription {
    ClientId client = 0;
    uint32_t camera_index = 0;
    proto::Delivery delivery = proto::DELIVERY_NEWEST;
    uint64_t step_credits = 0;
    std::shared_ptr<ClientLink> link;
  };
  Subscription* Find(ClientId client);
  std::vector<Subscription> subscriptions_;  // ordered by client id
};

}  // namespace sim4cv::session
