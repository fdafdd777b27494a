// The shared-memory link: requests and replies through this client's rings,
// frames read from the frame ring when the caller waits for one (the newest
// it has not yet been given, copied once into the caller's Frame). Configure
// and its answers rarely fit the rings' messages (docs/protocol.md 16.5), so
// they go over a TCP link to the same daemon, opened on first use.
#include <algorithm>

#include "../link.h"
#include "protocol/framing.h"
#include "sim4cv/shm_client.h"

namespace sim4cv::detail {
namespace {

using Clock = std::chrono::steady_clock;
using Envelope = proto::Envelope;

// While waiting for a frame, replies (an Error, say) are looked for this often.
constexpr auto kReplyPoll = std::chrono::milliseconds(5);
// A client that only reads frames sends a GetState this often, so the daemon
// (--shm-expiry-ms, 5 s by default) keeps its attachment; the State is dropped.
constexpr auto kKeepAlive = std::chrono::seconds(1);

// `view`'s metadata and pixels into `frame` (buffers reused).
void CopyFrame(const FrameView& view, const std::string& camera, proto::Frame& frame) {
  frame.Clear();
  frame.set_frame_id(view.frame_id());
  frame.set_sim_time(view.sim_time());
  frame.set_camera(camera);
  frame.set_width(view.width());
  frame.set_height(view.height());
  frame.set_render_end_mono_ns(view.render_end_mono_ns());
  for (const channels::ChannelInfo& info : channels::kPixelChannels) {
    const auto image = view.image(info.id);
    if (!image) continue;
    proto::Image& out = *frame.add_images();
    out.set_channel(info.id);
    out.set_format(image->format);
    out.set_element(image->element);
    out.set_components(image->components);
    out.set_stride(image->stride);
    out.set_data(image->data, static_cast<std::size_t>(image->stride) * image->height);
  }
  for (const ShmBox& box : view.boxes()) {
    proto::Box& out = *frame.add_boxes();
    out.set_object_id(box.object_id);
    out.set_object_class(static_cast<proto::ObjectClass>(box.object_class));
    out.set_x(box.x);
    out.set_y(box.y);
    out.set_width(box.width);
    out.set_height(box.height);
    out.set_visibility(box.visibility);
    out.set_visible_pixels(box.visible_pixels);
  }
}

class ShmLink : public Link {
 public:
  explicit ShmLink(const std::string& name) : address_("shm://" + name) {
    shm_.Open(name);
    camera_ = shm_.camera();  // fixed for the ring's life: read once, not per frame
  }

  const std::string& address() const override { return address_; }

  proto::Welcome Hello(const std::string& client_name, uint32_t protocol_version, Deadline deadline) override {
    client_name_ = client_name;
    welcome_ = shm_.Hello(client_name, Until(deadline), protocol_version);
    return welcome_;
  }

  void Send(const Envelope& envelope) override {
    shm_.SendEnvelope(envelope);
    last_send_ = Clock::now();
  }
  void SendRaw(const void* data, std::size_t size) override { shm_.SendRaw(data, size); }

  bool Receive(Envelope& out, Deadline deadline, bool frame_wanted) override {
    KeepAlive();
    if (!frame_wanted) return Reply(out, deadline);
    for (;;) {
      if (Reply(out, Clock::now())) return true;
      if (shm_.newest_frame_id() > last_frame_id_ && TakeNewest(out)) return true;
      const auto now = Clock::now();
      if (now >= deadline) return false;
      shm_.WaitForFrame(last_frame_id_, std::min(Until(deadline), kReplyPoll));
      KeepAlive();
    }
  }

  Link& configure_link() override {
    if (tcp_ && tcp_->open()) return *tcp_;
    const auto tcp = std::find_if(welcome_.transports().begin(), welcome_.transports().end(),
                                  [](const proto::TransportInfo& t) { return t.kind() == proto::TRANSPORT_KIND_TCP; });
    if (tcp == welcome_.transports().end()) {
      throw ConnectionError("Configure over " + address_ +
                            " goes through the daemon's TCP port, but its Welcome lists none (send Hello first)");
    }
    const Deadline deadline = Clock::now() + std::chrono::seconds(5);
    tcp_ = OpenTcpLink("127.0.0.1", static_cast<uint16_t>(std::stoul(tcp->address())), deadline,
                       wire::kDefaultMaxMessageBytes);
    tcp_->Hello(client_name_ + "-configure", 0, deadline);
    return *tcp_;
  }

  bool open() const override { return shm_.is_open(); }
  void Close() override {
    if (tcp_) tcp_->Close();
    shm_.Close();
  }
  ShmClient* shm() override { return &shm_; }

 private:
  void KeepAlive() {
    if (Clock::now() - last_send_ < kKeepAlive || !shm_.attached()) return;
    Envelope request;
    request.mutable_get_state();
    Send(request);
    ++keepalive_states_;
  }

  // The next reply that is not the answer to a keep-alive.
  bool Reply(Envelope& out, Deadline deadline) {
    while (shm_.ReceiveReply(out, Until(deadline))) {
      // Frames from the subscription on: one the ring already held when it
      // was answered (other clients stepped) is not the answer to a Step of
      // this one; taking it would leave a lockstep client one frame behind.
      if (out.has_subscribed()) last_frame_id_ = shm_.newest_frame_id();
      if (!(out.has_state() && keepalive_states_ > 0)) return true;
      --keepalive_states_;
    }
    return false;
  }

  // The newest frame, if it is newer than the last one taken; false if the
  // daemon overwrote it while it was copied (the caller looks again).
  bool TakeNewest(Envelope& out) {
    if (!shm_.AcquireNewest(view_) || view_.frame_id() <= last_frame_id_) return false;
    CopyFrame(view_, camera_, *out.mutable_frame());
    if (view_.stale()) return false;
    last_frame_id_ = view_.frame_id();
    return true;
  }

  std::string address_;
  std::string client_name_;
  ShmClient shm_;
  std::string camera_;  // the ring's camera
  FrameView view_;
  uint64_t last_frame_id_ = 0;
  Clock::time_point last_send_ = Clock::now();
  uint32_t keepalive_states_ = 0;
  proto::Welcome welcome_;
  std::unique_ptr<Link> tcp_;
};

}  // namespace

std::unique_ptr<Link> OpenShmLink(const std::string& name) { return std::make_unique<ShmLink>(name); }

}  // namespace sim4cv::detail
