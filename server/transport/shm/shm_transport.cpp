// The shared-memory Transport: the frame ring's writer (called by the sim
// thread) plus one "shm" thread that attaches clients (ShmListener), drains
// each client's request ring when its doorbell rings, runs its messages
// through its own ClientProtocol exactly as TCP does, writes the replies into
// its response ring (through the session's ShmClientLink, which the sim
// thread answers through as well), and ends the attachment of a client that
// closed its socket (died), broke its ring's rules or stayed silent for
// --shm-expiry-ms. Nothing a client does reaches another client: each has its
// own area, its own doorbell and at most one ring's worth of requests taken
// per turn.
#include "server/transport/shm/shm_transport.h"

#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <map>
#include <optional>
#include <set>
#include <thread>
#include <vector>

#include "protocol/shm_sync.h"
#include "server/common/diagnostics.h"
#include "server/session/client_protocol.h"
#include "server/transport/shm/shm_client_area.h"
#include "server/transport/shm/shm_client_link.h"
#include "server/transport/shm/shm_listener.h"
#include "server/transport/shm/shm_region.h"
#include "server/transport/shm/shm_ring_writer.h"

namespace sim4cv::transport {
namespace {

using Clock = std::chrono::steady_clock;
using Outcome = session::ClientProtocol::Outcome;

// epoll keys: an attachment's serial times 2, plus 1 for its doorbell.
constexpr uint64_t kListenKey = UINT64_MAX, kStopKey = UINT64_MAX - 1;
constexpr auto kAcceptRest = std::chrono::milliseconds(limits::kShmAcceptRestMs);

struct Attachment {
  int socket = -1;
  int doorbell = -1;  // eventfd: the client writes to it after adding requests
  std::shared_ptr<ShmClientArea> area;
  Clock::time_point last_heard;
  // One "connection" of ClientProtocol: replaced after a fatal Error, like a TCP reconnect.
  session::ClientId id = 0;
  std::shared_ptr<ShmClientLink> link;  // always set; a closed one is replaced on the next message
  std::unique_ptr<session::ClientProtocol> protocol;
  bool welcomed = false;
};

ShmRegionParams RegionParams(const ShmOptions& o) {
  return {o.camera, o.width, o.height, o.slot_count, o.expiry_ms, o.channel_mask};
}

class ShmTransport : public Transport {
 public:
  explicit ShmTransport(const ShmOptions& options)
      : options_(options),
        region_(std::make_shared<ShmRegion>(RegionParams(options))),
        listener_(std::make_unique<ShmListener>(options.name)) {
    epoll_ = epoll_create1(EPOLL_CLOEXEC);
    stop_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (epoll_ < 0 || stop_ < 0) throw std::runtime_error(std::string("shm transport: ") + std::strerror(errno));
    Watch(listener_->fd(), kListenKey);
    Watch(stop_, kStopKey);
  }

  ~ShmTransport() override {
    Stop();
    close(stop_);
    close(epoll_);
  }

  proto::TransportInfo info() const override {
    proto::TransportInfo info;
    info.set_kind(proto::TRANSPORT_KIND_SHM);
    info.set_address(options_.name);
    return info;
  }

  std::string listening_field() const override { return "shm=" + options_.name; }

  void Start(const session::ServerContext& context) override {
    const int camera = context.scene.FindCamera(options_.camera);
    if (camera < 0) throw std::invalid_argument("--shm-camera '" + options_.camera + "' is not a camera of the scene");
    const auto& spec = context.scene.cameras[static_cast<std::size_t>(camera)];
    if (spec.width != options_.width || spec.height != options_.height) {
      throw std::invalid_argument("shared-memory ring sized for " + std::to_string(options_.width) + "x" +
                                  std::to_string(options_.height) + " but camera '" + options_.camera + "' is " +
                                  std::to_string(spec.width) + "x" + std::to_string(spec.height));
    }
    context_ = &context;
    writer_ = std::make_shared<ShmRingWriter>(region_, static_cast<uint32_t>(camera));
    // The ring's own newest-frame subscription: the camera renders every
    // frame, with its channels and the boxes every slot carries.
    writer_id_ = session::NewClientId();
    context.commands.Post(
        {writer_id_, session::SubscribeCommand{static_cast<uint32_t>(camera), proto::DELIVERY_NEWEST,
                                               options_.channel_mask | channels::Bit(proto::CHANNEL_BOXES), writer_}});
    thread_ = std::thread([this] { Run(); });
  }

  void Stop() override {
    if (stopped_) return;
    stopped_ = true;
    if (thread_.joinable()) {
      stopping_ = true;
      const uint64_t one = 1;
      [[maybe_unused]] const auto ignored = write(stop_, &one, sizeof one);
      thread_.join();
    }
    listener_.reset();  // no more attachments
    while (!clients_.empty()) Detach(clients_.begin()->first, nullptr, "the daemon stops");
    if (context_) context_->commands.Post({writer_id_, session::DisconnectCommand{}});
    if (writer_) writer_->Close();
  }

 private:
  void Watch(int fd, uint64_t key) {
    epoll_event event{};
    event.events = EPOLLIN;
    event.data.u64 = key;
    if (epoll_ctl(epoll_, EPOLL_CTL_ADD, fd, &event) != 0)
      throw std::runtime_error(std::string("shm transport: epoll_ctl: ") + std::strerror(errno));
  }

  void Run() {
    const int idle_ms = static_cast<int>(std::min<uint32_t>(100, std::max<uint32_t>(1, options_.expiry_ms / 4)));
    std::array<epoll_event, 64> events{};
    while (!stopping_) {
      const int timeout = !ready_.empty() ? 0 : idle_ms;
      const int count = epoll_wait(epoll_, events.data(), static_cast<int>(events.size()), timeout);
      const Clock::time_point now = Clock::now();
      for (int i = 0; i < count; ++i) OnEvent(events[static_cast<std::size_t>(i)], now);
      if (count == 0) {
        // Quiet: look at every ring once, for clients that wrote without ringing.
        for (const auto& [serial, a] : clients_) ready_.insert(serial);
      }
      ResumeListening(now);
      DrainReady(now);
      if (links_closed_.exchange(false)) EndSessionsClosedBySim();
      ExpireSilent(now);
    }
  }

  void OnEvent(const epoll_event& event, Clock::time_point now) {
    const uint64_t key = event.data.u64;
    if (key == kStopKey) {  // Stop or OnLinkClosed: clear the count (the loop looks at the flags)
      uint64_t count = 0;
      [[maybe_unused]] const auto ignored = read(stop_, &count, sizeof count);
      return;
    }
    if (key == kListenKey) return AcceptAll(now);
    const uint64_t serial = key / 2;
    const auto it = clients_.find(serial);
    if (it == clients_.end()) return;
    Attachment& a = *it->second;
    if (key % 2 == 1) {  // the doorbell: drain its count, then the ring
      uint64_t rings = 0;
      [[maybe_unused]] const auto ignored = read(a.doorbell, &rings, sizeof rings);
      ready_.insert(serial);
      return;
    }
    // The socket: clients send nothing on it, so readable means closed (or junk, discarded).
    char junk[256];
    const ssize_t got = recv(a.socket, junk, sizeof junk, MSG_DONTWAIT);
    if (got == 0 || (got < 0 && errno != EAGAIN && errno != EINTR)) {
      Detach(serial, nullptr, "closed its socket (the process ended or called Close)");
    }
  }

  void AcceptAll(Clock::time_point now) {
    for (;;) {
      const int connection = listener_->Accept();
      if (connection < 0) {
        if (errno == EAGAIN || errno == EINTR || errno == ECONNABORTED) return;
        // Out of descriptors (or memory): rest instead of spinning on the same pending connection.
        LOG_INFO("shared-memory attach not accepted: " << std::strerror(errno) << "; retrying in "
                                                       << kAcceptRest.count() << " ms");
        epoll_ctl(epoll_, EPOLL_CTL_DEL, listener_->fd(), nullptr);
        listen_rest_until_ = now + kAcceptRest;
        return;
      }
      Attach(connection, now);
    }
  }

  void ResumeListening(Clock::time_point now) {
    if (!listen_rest_until_ || now < *listen_rest_until_ || !listener_) return;
    listen_rest_until_.reset();
    Watch(listener_->fd(), kListenKey);
  }

  void Attach(int connection, Clock::time_point now) {
    std::string why;
    if (!ShmListener::PeerAllowed(connection, why)) {
      LOG_INFO("shared-memory attach refused: " << why);
      ShmListener::Refuse(connection, "sim4cvd refused: " + why);
      close(connection);
      return;
    }
    if (clients_.size() >= options_.max_clients) {
      context_->counters.Add("shm.refused");
      LOG_INFO("shared-memory attach refused: all " << options_.max_clients << " client places are in use");
      ShmListener::Refuse(connection, "sim4cvd refused: all " + std::to_string(options_.max_clients) +
                                          " shared-memory client places are in use; try again later or use TCP");
      close(connection);
      return;
    }
    auto a = std::make_unique<Attachment>();
    a->socket = connection;
    try {
      a->area = std::make_shared<ShmClientArea>(connection);
    } catch (const std::exception& error) {
      LOG_INFO("shared-memory attach refused: " << error.what());
      ShmListener::Refuse(connection, std::string("sim4cvd refused: ") + error.what());
      close(connection);
      return;
    }
    a->doorbell = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    shm::ShmAttach attach{};
    std::memcpy(attach.magic, SIM4CV_SHM_ATTACH_MAGIC, sizeof attach.magic);
    attach.layout_version = shm::kShmLayoutVersion;
    attach.frames_bytes = region_->geometry().total_bytes;
    attach.area_bytes = shm::kAreaBytes;
    const int fds[3] = {region_->fd(), a->area->fd(), a->doorbell};
    const uint64_t serial = next_serial_++;
    if (a->doorbell < 0 || !ShmListener::Send(connection, attach, fds, 3)) {
      LOG_INFO("shared-memory attach failed: " << std::strerror(errno));
      if (a->doorbell >= 0) close(a->doorbell);
      close(connection);
      return;
    }
    a->area->CloseFd();  // the client has its own descriptor; the daemon keeps the mapping
    a->last_heard = now;
    a->link = NewLink(*a);
    Watch(a->socket, serial * 2);
    Watch(a->doorbell, serial * 2 + 1);
    clients_.emplace(serial, std::move(a));
  }

  std::shared_ptr<ShmClientLink> NewLink(const Attachment& a) {
    return std::make_shared<ShmClientLink>(a.area, context_->counters, [this] { OnLinkClosed(); });
  }

  // Ends a client's attachment: `error` (if any) is its last response, then
  // its area is marked closed, its session ends and its descriptors close.
  void Detach(uint64_t serial, const proto::Envelope* error, const std::string& reason) {
    const auto it = clients_.find(serial);
    if (it == clients_.end()) return;
    Attachment& a = *it->second;
    LOG_INFO("shared-memory client (session " << a.id << ") detached: " << reason);
    a.link->EndAttachment(error);
    if (a.protocol) a.protocol->Disconnect();
    epoll_ctl(epoll_, EPOLL_CTL_DEL, a.socket, nullptr);
    epoll_ctl(epoll_, EPOLL_CTL_DEL, a.doorbell, nullptr);
    close(a.socket);
    close(a.doorbell);
    ready_.erase(serial);
    clients_.erase(it);
  }

  // Takes at most one ring's worth of requests from each client that rang:
  // one client's flood cannot hold back the others.
  void DrainReady(Clock::time_point now) {
    std::set<uint64_t> now_ready, again;
    now_ready.swap(ready_);
    for (const uint64_t serial : now_ready) {
      const auto it = clients_.find(serial);
      if (it == clients_.end()) continue;
      Attachment& a = *it->second;
      ShmClientArea::Take take = ShmClientArea::Take::kEmpty;
      std::string why;
      for (uint32_t n = 0; n < limits::kShmRequestsPerTurn; ++n) {
        const uint8_t* data = nullptr;
        uint32_t size = 0;
        take = a.area->Next(data, size, why);
        if (take != ShmClientArea::Take::kMessage) break;
        Handle(a, data, size, now);
      }
      if (take == ShmClientArea::Take::kBroken) {
        context_->counters.Add("shm.rings_broken");
        proto::Envelope error;
        session::ClientProtocol::Refuse(proto::ERROR_CODE_MALFORMED_MESSAGE,
                                        "the shared-memory request ring of this client is broken: " + why +
                                            "; attach again",
                                        true, error);
        Detach(serial, &error, "broke its request ring: " + why);
      } else if (take == ShmClientArea::Take::kMessage) {
        again.insert(serial);  // more than a ring's worth: the rest next turn
      }
    }
    ready_.insert(again.begin(), again.end());
  }

  void Handle(Attachment& a, const uint8_t* data, uint32_t size, Clock::time_point now) {
    a.last_heard = now;
    // A fatal Error from the sim thread ended the session: this message starts the next one.
    if (a.protocol && a.link->closed()) EndSession(a, a.link->fatal_message());
    if (!a.protocol) {
      if (a.link->closed()) a.link = NewLink(a);
      a.id = session::NewClientId();
      // No mailbox: the client's frames are the ring's.
      a.protocol = std::make_unique<session::ClientProtocol>(a.id, *context_, a.link, nullptr);
      // Attached through the socket whose peer credentials ShmListener
      // checked: the daemon's own user, who can read the token file anyway.
      a.protocol->MarkAuthenticated();
      a.welcomed = false;
      LOG_INFO("client " << a.id << " connected over shared memory " << options_.name);
    }
    // Every frame the ring published for this client since its last message
    // is delivered: it is in the ring the moment it is offered.
    a.protocol->OnFramesSent(a.link->TakeFramesOffered());

    Outcome outcome;
    const bool parsed = request_.ParseFromArray(data, static_cast<int>(size));
    const std::string refusal =
        parsed && a.welcomed && request_.has_subscribe() ? RingRefusal(request_.subscribe()) : std::string();
    if (!parsed) {
      outcome = session::ClientProtocol::Refuse(
          proto::ERROR_CODE_MALFORMED_MESSAGE,
          "the " + std::to_string(size) + " bytes of a shared-memory request slot are not a valid Envelope", true,
          reply_);
    } else if (!refusal.empty()) {
      outcome = session::ClientProtocol::Refuse(proto::ERROR_CODE_INVALID_ARGUMENT, refusal, false, reply_);
    } else {
      outcome = a.protocol->Handle(request_, reply_);
      if (reply_.has_welcome()) a.welcomed = true;
    }
    if (outcome == Outcome::kNoReply) return;
    a.link->Reply(reply_);
    if (outcome == Outcome::kReplyAndClose) EndSession(a, reply_.error().message());
  }

  // Why the ring cannot serve `subscribe` (empty if it can): frames of one
  // camera, with only the channels of --shm-channels. Other problems (an
  // unknown camera, bad channel numbers) are ClientProtocol's to answer as over TCP.
  std::string RingRefusal(const proto::Subscribe& subscribe) const {
    if (subscribe.camera() != options_.camera) {
      if (!context_->world.HasCamera(subscribe.camera())) return "";  // ClientProtocol's UNKNOWN_CAMERA
      return "Subscribe.camera is '" + subscribe.camera() + "' but the shared-memory ring " + options_.name +
             " carries camera '" + options_.camera + "' (daemon flag --shm-camera); subscribe to '" + options_.camera +
             "' here, or use TCP for other cameras";
    }
    for (const int channel : subscribe.channels()) {
      const channels::ChannelInfo* info = channels::Find(channel);
      if (info == nullptr || channels::Has(options_.channel_mask, channel)) continue;  // BOXES, unknown: ClientProtocol's
      return "Subscribe.channels asks for " + proto::Channel_Name(channel) + " but the shared-memory ring " +
             options_.name + " carries only " + channels::Names(options_.channel_mask) +
             " (daemon flag --shm-channels); leave " + proto::Channel_Name(channel) +
             " out, subscribe to it over TCP, or start sim4cvd with --shm-channels including " + std::string(info->name);
    }
    return "";
  }

  // After a fatal Error (from ClientProtocol or the sim thread): the client's
  // next message starts a new session, which must begin with Hello. The
  // attachment stays, so the client can read the Error.
  void EndSession(Attachment& a, const std::string& error) {
    LOG_INFO("client " << a.id << " refused: " << error);
    a.link->Close();
    a.protocol->Disconnect();
    a.protocol.reset();
  }

  // Sim thread (ShmClientLink::OfferReply sent a fatal Error): the shm thread
  // ends that session on its next turn, without waiting for a message.
  void OnLinkClosed() {
    links_closed_ = true;
    const uint64_t one = 1;
    [[maybe_unused]] const auto ignored = write(stop_, &one, sizeof one);  // wakes epoll_wait
  }

  void EndSessionsClosedBySim() {
    for (auto& [serial, a] : clients_) {
      if (a->protocol && a->link->closed()) EndSession(*a, a->link->fatal_message());
    }
  }

  void ExpireSilent(Clock::time_point now) {
    const auto limit = std::chrono::milliseconds(options_.expiry_ms);
    std::vector<uint64_t> silent;
    for (const auto& [serial, a] : clients_) {
      if (now - a->last_heard > limit) silent.push_back(serial);
    }
    for (const uint64_t serial : silent) {
      context_->counters.Add("shm.clients_expired");
      proto::Envelope error;
      const std::string message = "this shared-memory client sent nothing for " + std::to_string(options_.expiry_ms) +
                                  " ms (daemon flag --shm-expiry-ms) and was disconnected; send Hello to attach again";
      session::ClientProtocol::Refuse(proto::ERROR_CODE_INVALID_STATE, message, true, error);
      Detach(serial, &error, "sent nothing for " + std::to_string(options_.expiry_ms) + " ms (--shm-expiry-ms)");
    }
  }

  ShmOptions options_;
  std::shared_ptr<ShmRegion> region_;
  std::unique_ptr<ShmListener> listener_;
  std::shared_ptr<ShmRingWriter> writer_;
  const session::ServerContext* context_ = nullptr;
  session::ClientId writer_id_ = 0;
  int epoll_ = -1;
  int stop_ = -1;  // eventfd: Stop and OnLinkClosed wake the thread through it
  uint64_t next_serial_ = 1;
  std::map<uint64_t, std::unique_ptr<Attachment>> clients_;  // by serial; shm thread only (and Stop after it)
  std::set<uint64_t> ready_;                                  // rang their doorbell, or have more to read
  std::optional<Clock::time_point> listen_rest_until_;
  proto::Envelope request_, reply_;
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  std::atomic<bool> links_closed_{false};  // a link closed itself (OnLinkClosed)
  bool stopped_ = false;
};

}  // namespace

std::unique_ptr<Transport> MakeShmTransport(const ShmOptions& options) {
  return std::make_unique<ShmTransport>(options);
}

}  // namespace sim4cv::transport
