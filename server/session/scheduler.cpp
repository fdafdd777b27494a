#include "server/session/scheduler.h"

#include <algorithm>

namespace sim4cv::session {

Scheduler::Subscription* Scheduler::Find(ClientId client) {
  const auto it = std::find_if(subscriptions_.begin(), subscriptions_.end(),
                               [&](const Subscription& s) { return s.client == client; });
  return it == subscriptions_.end() ? nullptr : &*it;
}

void Scheduler::Subscribe(ClientId client, uint32_t camera_index, proto::Delivery delivery,
                          channels::ChannelSet channels, std::shared_ptr<ClientLink> link,
                          std::shared_ptr<const MailboxGate> gate, int64_t min_interval_ns) {
  Subscription subscription{client, camera_index, delivery, channels, 0, std::move(link), std::move(gate)};
  subscription.min_interval_ns = min_interval_ns;
  Subscription* existing = Find(client);
  if (existing) {
    // A replaced subscription keeps no credits: they were for the old one.
    *existing = std::move(subscription);
    return;
  }
  const auto position = std::lower_bound(subscriptions_.begin(), subscriptions_.end(), client,
                                         [](const Subscription& s, ClientId id) { return s.client < id; });
  subscriptions_.insert(position, std::move(subscription));
}

void Scheduler::AddStep(ClientId client) {
  Subscription* s = Find(client);
  if (s && s->delivery == proto::DELIVERY_LOCKSTEP) ++s->step_credits;
}

void Scheduler::Remove(ClientId client) {
  std::erase_if(subscriptions_, [&](const Subscription& s) { return s.client == client; });
}

bool Scheduler::LockstepReady() const {
  bool any_lockstep = false;
  for (const auto& s : subscriptions_) {
    if (s.delivery != proto::DELIVERY_LOCKSTEP || Dead(s.camera_index)) continue;
    if (s.step_credits == 0 || (s.gate && s.gate->full())) return false;
    any_lockstep = true;
  }
  return any_lockstep;
}

void Scheduler::ConsumeSteps() {
  for (auto& s : subscriptions_) {
    if (s.delivery == proto::DELIVERY_LOCKSTEP && s.step_credits > 0) --s.step_credits;
  }
}

channels::ChannelSet Scheduler::ChannelsWanted(uint32_t camera_index) const {
  if (Dead(camera_index)) return 0;
  channels::ChannelSet wanted = 0;
  for (const auto& s : subscriptions_) {
    // A subscription always wants something: a frame without pixels still carries its metadata.
    if (s.camera_index == camera_index && Due(s)) wanted |= s.channels | channels::Bit(proto::CHANNEL_UNSPECIFIED);
  }
  return wanted;
}

channels::ChannelSet Scheduler::ChannelsSentFromFrame(uint32_t camera_index, const ClientLink* except) const {
  channels::ChannelSet wanted = 0;
  for (const auto& s : subscriptions_) {
    if (s.camera_index == camera_index && s.link && s.link.get() != except && s.link->SendsFramePixels()) {
      wanted |= s.channels;
    }
  }
  return wanted;
}

std::optional<uint32_t> Scheduler::CameraOf(ClientId client) const {
  for (const auto& s : subscriptions_) {
    if (s.client == client) return s.camera_index;
  }
  return std::nullopt;
}

void Scheduler::Deliver(const FrameRef& frame) {
  if (!observer_) {
    OfferToSubscribers(frame);
    return;
  }
  observer_->OfferFrame(frame);
  held_.push_back(frame);
}

void Scheduler::ReleaseFrames() {
  for (const FrameRef& frame : held_) OfferToSubscribers(frame);
  held_.clear();
}

void Scheduler::OfferToSubscribers(const FrameRef& frame) {
  for (auto& s : subscriptions_) {
    // A null link (a subscriber fed some other way, e.g. the shared-memory ring) only steps.
    if (s.camera_index != frame->camera_index || !s.link || !Due(s)) continue;
    s.link->OfferFrame(frame);
    if (s.min_interval_ns > 0) {
      // Keep the cap's phase while frames come often enough; after a gap (a
      // paused lockstep simulation) start again from now, without a burst.
      const bool in_phase = now_ns_ - s.next_due_ns < s.min_interval_ns;
      s.next_due_ns = (in_phase ? s.next_due_ns : now_ns_) + s.min_interval_ns;
    }
  }
}

std::vector<std::shared_ptr<ClientLink>> Scheduler::SetCameraDead(uint32_t camera_index, bool dead) {
  if (dead_cameras_.size() <= camera_index) dead_cameras_.resize(camera_index + 1, false);
  dead_cameras_[camera_index] = dead;
  std::vector<std::shared_ptr<ClientLink>> links;
  for (const auto& s : subscriptions_) {
    if (s.camera_index == camera_index && s.link) links.push_back(s.link);
  }
  return links;
}

std::vector<std::shared_ptr<ClientLink>> Scheduler::DropCamerasFrom(uint32_t camera_index) {
  std::vector<std::shared_ptr<ClientLink>> links;
  std::erase_if(subscriptions_, [&](const Subscription& s) {
    if (s.camera_index < camera_index) return false;
    if (s.link) links.push_back(s.link);
    return true;
  });
  if (dead_cameras_.size() > camera_index) dead_cameras_.resize(camera_index);
  return links;
}

}  // namespace sim4cv::session
