// The shared-memory Transport: the frame ring's writer (called by the sim
// thread) plus one "shm" thread that drains the reply ring, runs each client
// token's messages through its own ClientProtocol exactly as TCP does, writes
// the replies into the client's response entry (through the session's
// ShmClientLink, which the sim thread answers through as well), and
// disconnects clients that have been silent for --shm-expiry-ms.
#include "server/transport/shm/shm_transport.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <map>
#include <thread>

#include "protocol/shm_sync.h"
#include "server/common/log.h"
#include "server/session/client_protocol.h"
#include "server/transport/shm/shm_client_link.h"
#include "server/transport/shm/shm_reply_reader.h"
#include "server/transport/shm/shm_responder.h"
#include "server/transport/shm/shm_ring_writer.h"

namespace sim4cv::transport {
namespace {

using Clock = std::chrono::steady_clock;
using Outcome = session::ClientProtocol::Outcome;

struct ShmSession {
  int entry = -1;  // response-area entry
  Clock::time_point last_heard;
  // One "connection": replaced after a fatal Error, like a TCP reconnect.
  session::ClientId id = 0;
  std::shared_ptr<ShmClientLink> link;
  session::FrameMailbox mailbox;  // unused: ClientProtocol needs one
  std::unique_ptr<session::ClientProtocol> protocol;
  bool welcomed = false;
};

ShmRegionParams RegionParams(const ShmOptions& o) {
  return {o.name,        o.camera,    o.width,       o.height, o.slot_count, o.reply_slot_count,
          o.max_clients, o.expiry_ms, o.channel_mask};
}

class ShmTransport : public Transport {
 public:
  explicit ShmTransport(const ShmOptions& options)
      : options_(options),
        region_(std::make_shared<ShmRegion>(RegionParams(options))),
        responder_(std::make_shared<ShmResponder>(region_)) {}

  ~ShmTransport() override { Stop(); }

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
    // The ring's own newest-frame subscription: the camera renders every frame.
    writer_id_ = session::NewClientId();
    context.commands.Post(
        {writer_id_, session::SubscribeCommand{static_cast<uint32_t>(camera), proto::DELIVERY_NEWEST, writer_}});
    reader_ =
        std::make_unique<ShmReplyReader>(region_, context.counters, std::chrono::microseconds(options_.reply_spin_us));
    thread_ = std::thread([this] { Run(); });
  }

  void Stop() override {
    if (stopped_) return;
    stopped_ = true;
    if (thread_.joinable()) {
      stopping_ = true;
      reader_->Wake();
      thread_.join();
    }
    for (auto& [token, s] : sessions_) {
      if (s->link) s->link->Close();
      if (s->protocol) s->protocol->Disconnect();
    }
    sessions_.clear();
    if (context_) context_->commands.Post({writer_id_, session::DisconnectCommand{}});
    if (writer_) writer_->Close();
    responder_->WakeAll();
    region_->Unlink();
  }

 private:
  void Run() {
    const auto idle_wait =
        std::chrono::milliseconds(std::min<uint32_t>(100, std::max<uint32_t>(1, options_.expiry_ms / 4)));
    while (!stopping_) {
      const uint32_t seen = reader_->futex_value();
      const Clock::time_point now = Clock::now();
      ShmReplyReader::Message message;
      ShmReplyReader::Result result;
      while ((result = reader_->Next(message, now)) == ShmReplyReader::Result::kMessage) Handle(message, now);
      if (links_closed_.exchange(false)) EndSessionsClosedBySim();
      ExpireSilent(now);
      if (stopping_) break;
      reader_->Wait(seen, result == ShmReplyReader::Result::kStalled ? std::chrono::milliseconds(1) : idle_wait);
    }
  }

  void Handle(const ShmReplyReader::Message& message, Clock::time_point now) {
    auto it = sessions_.find(message.token);
    if (it == sessions_.end()) {
      const int entry = responder_->Assign(message.token);
      if (entry < 0) {
        context_->counters.Add("shm.refused");
        LOG_INFO("shared-memory message from a new client refused: all " << options_.max_clients
                                                                         << " response entries are in use");
        return;
      }
      it = sessions_.emplace(message.token, std::make_unique<ShmSession>()).first;
      it->second->entry = entry;
    }
    ShmSession& s = *it->second;
    s.last_heard = now;
    // A fatal Error from the sim thread ended the session: this message starts the next one.
    if (s.protocol && s.link->closed()) EndSession(s, s.link->fatal_message());
    if (!s.protocol) {
      s.id = session::NewClientId();
      s.link = std::make_shared<ShmClientLink>(responder_, s.entry, context_->counters, [this] { OnLinkClosed(); });
      s.protocol = std::make_unique<session::ClientProtocol>(s.id, *context_, s.link, s.mailbox);
      s.welcomed = false;
      LOG_INFO("client " << s.id << " connected over shared memory " << options_.name);
    }
    // Frames the ring received for this client since its last message; more
    // than the Step limit cannot matter.
    const uint64_t delivered =
        std::min<uint64_t>(s.link->TakeFramesOffered(), session::FrameMailbox::kMaxLockstepBacklog);
    for (uint64_t n = 0; n < delivered; ++n) s.protocol->OnFrameSent();

    Outcome outcome;
    const bool parsed = request_.ParseFromArray(message.data, static_cast<int>(message.size));
    const std::string refusal =
        parsed && s.welcomed && request_.has_subscribe() ? RingRefusal(request_.subscribe()) : std::string();
    if (!parsed) {
      outcome = session::ClientProtocol::Refuse(
          proto::ERROR_CODE_MALFORMED_MESSAGE,
          "the " + std::to_string(message.size) + " bytes of a shared-memory reply slot are not a valid Envelope", true,
          reply_);
    } else if (!refusal.empty()) {
      outcome = session::ClientProtocol::Refuse(proto::ERROR_CODE_INVALID_ARGUMENT, refusal, false, reply_);
    } else {
      outcome = s.protocol->Handle(request_, reply_);
      if (reply_.has_welcome()) s.welcomed = true;
    }
    if (outcome == Outcome::kNoReply) return;
    s.link->Reply(reply_);
    if (outcome == Outcome::kReplyAndClose) EndSession(s, reply_.error().message());
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
      const bool pixels = channel >= proto::CHANNEL_RGB && channel <= proto::CHANNEL_MASK;
      if (!pixels || (options_.channel_mask & shm::ChannelBit(static_cast<uint32_t>(channel))) != 0) continue;
      return "Subscribe.channels asks for " + proto::Channel_Name(channel) + " but the shared-memory ring " +
             options_.name + " carries only " + shm::ChannelFlagValue(options_.channel_mask) +
             " (daemon flag --shm-channels); leave " + proto::Channel_Name(channel) +
             " out, subscribe to it over TCP, or start sim4cvd with --shm-channels including " +
             shm::ChannelFlagName(static_cast<uint32_t>(channel));
    }
    return "";
  }

  // After a fatal Error (from ClientProtocol or the sim thread): the client's
  // next message starts a new session, which must begin with Hello.
  void EndSession(ShmSession& s, const std::string& error) {
    LOG_INFO("client " << s.id << " refused: " << error);
    s.link->Close();
    s.protocol->Disconnect();
    s.protocol.reset();
  }

  // Sim thread (ShmClientLink::OfferReply sent a fatal Error): the shm thread
  // ends that session on its next turn, without waiting for a message.
  void OnLinkClosed() {
    links_closed_ = true;
    reader_->Wake();
  }

  void EndSessionsClosedBySim() {
    for (auto& [token, s] : sessions_) {
      if (s->protocol && s->link->closed()) EndSession(*s, s->link->fatal_message());
    }
  }

  void ExpireSilent(Clock::time_point now) {
    const auto limit = std::chrono::milliseconds(options_.expiry_ms);
    for (auto it = sessions_.begin(); it != sessions_.end();) {
      ShmSession& s = *it->second;
      if (now - s.last_heard <= limit) {
        ++it;
        continue;
      }
      if (s.protocol) {
        LOG_INFO("client " << s.id << " sent nothing over shared memory for " << options_.expiry_ms
                           << " ms (--shm-expiry-ms); disconnected");
        s.protocol->Disconnect();
      }
      if (s.link) s.link->Close();  // before the entry can go to another client
      context_->counters.Add("shm.clients_expired");
      responder_->Free(s.entry);
      it = sessions_.erase(it);
    }
  }

  ShmOptions options_;
  std::shared_ptr<ShmRegion> region_;
  std::shared_ptr<ShmResponder> responder_;  // shared with the sessions' links
  std::shared_ptr<ShmRingWriter> writer_;
  std::unique_ptr<ShmReplyReader> reader_;
  const session::ServerContext* context_ = nullptr;
  session::ClientId writer_id_ = 0;
  std::map<uint64_t, std::unique_ptr<ShmSession>> sessions_;  // by client token; shm thread only
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
