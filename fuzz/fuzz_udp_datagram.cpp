// Fuzz target: the daemon's UDP datagram path (server/transport/udp), without
// the socket. The input is a series of datagrams (records, fuzz_input.h), each
// from one of four sender addresses chosen by its first byte. Each goes the
// way UdpTransport::HandleDatagram and Dispatch send it: parsed as one
// Envelope; a FrameChunk from a client dropped; from an unregistered address
// only a Hello registers (a UdpPeer with its own ClientProtocol); Step,
// Controls and TrackerOutput through the peer's SequenceFilter; the rest to
// the peer's protocol; a fatal Error unregisters the peer. Those two
// functions live in the transport's socket-owning class, so their few lines
// of routing are repeated here; the decoding and every check are the real ones.
#include <netinet/in.h>

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "fuzz/fuzz_input.h"
#include "fuzz/protocol_harness.h"
#include "protocol/framing.h"
#include "server/transport/udp/udp_peer.h"

namespace {

using sim4cv::session::ClientProtocol;
using sim4cv::transport::UdpPeer;
using Kind = sim4cv::proto::Envelope::KindCase;
constexpr std::size_t kSenders = 4;
constexpr std::size_t kMaxDatagramBytes = 65000;  // UdpOptions' default

sim4cv::transport::PeerAddress Address(std::size_t sender) {
  sim4cv::transport::PeerAddress address;
  auto* in = reinterpret_cast<sockaddr_in*>(&address.storage);
  in->sin_family = AF_INET;
  in->sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  in->sin_port = htons(static_cast<uint16_t>(40000 + sender));
  address.length = sizeof(sockaddr_in);
  return address;
}

class Daemon {
 public:
  ~Daemon() {
    for (auto& peer : peers_) {
      if (peer) peer->Close(true);
    }
  }

  void Receive(std::size_t sender, const uint8_t* data, std::size_t size) {
    std::shared_ptr<UdpPeer>& peer = peers_[sender];
    if (!request_.ParseFromArray(data, static_cast<int>(size))) return;  // counted; an Error if registered
    if (request_.has_frame_chunk()) return;                              // only the daemon sends chunks
    if (!peer) return Stranger(sender);
    ClientProtocol::Outcome outcome;
    switch (request_.kind_case()) {
      case Kind::KIND_NOT_SET:
        return;  // keep-alive
      case Kind::kHello:
        if (request_.hello().protocol_version() == sim4cv::wire::kProtocolVersion) {
          reply_.Clear();
          ClientProtocol::FillWelcome(sim4cv::fuzz::SharedHarness().context(), peer->client(),
                                      *reply_.mutable_welcome());
          return Send();
        }
        break;
      case Kind::kStep:
      case Kind::kControls:
      case Kind::kTrackerOutput:
        if (!peer->sequence().Accept(request_.sequence())) return;  // late or duplicated
        break;
      default:
        break;
    }
    outcome = peer->protocol().Handle(request_, reply_);
    if (outcome == ClientProtocol::Outcome::kNoReply) return;
    Send();
    if (ClientProtocol::EndsConnection(reply_)) Unregister(sender);
  }

  // What the sim thread offered each peer since: sent, a fatal one unregisters.
  void SendOffered() {
    for (std::size_t sender = 0; sender < kSenders; ++sender) {
      if (!peers_[sender]) continue;
      peers_[sender]->TakeOfferedReplies(offered_);
      for (sim4cv::proto::Envelope& reply : offered_) {
        reply_.Swap(&reply);
        Send();
        if (ClientProtocol::EndsConnection(reply_)) {
          Unregister(sender);
          break;
        }
      }
    }
  }

 private:
  void Stranger(std::size_t sender) {
    if (!request_.has_hello()) return;  // NOT_HANDSHAKEN (rate-limited), or nothing for a late keep-alive
    auto peer = std::make_shared<UdpPeer>(sim4cv::session::NewClientId(), Address(sender),
                                          sim4cv::fuzz::SharedHarness().context(), wakeup_, kMaxDatagramBytes,
                                          std::chrono::steady_clock::now());
    peer->Start();
    peer->protocol().Handle(request_, reply_);
    Send();
    if (!reply_.has_welcome()) {
      peer->Close(false);  // refused: never registered
      return;
    }
    peers_[sender] = std::move(peer);
  }

  void Unregister(std::size_t sender) {
    peers_[sender]->Close(true);
    peers_[sender].reset();
  }

  void Send() {
    reply_bytes_.clear();
    reply_.AppendToString(&reply_bytes_);  // what SendReply puts in the datagram
  }

  // One eventfd for the process, as the transport has one for all its peers;
  // cleared before each input as the transport's thread clears it before it looks for work.
  static std::shared_ptr<sim4cv::transport::Wakeup> SharedWakeup() {
    static const auto wakeup = std::make_shared<sim4cv::transport::Wakeup>();
    wakeup->Clear();
    return wakeup;
  }

  std::shared_ptr<sim4cv::transport::Wakeup> wakeup_ = SharedWakeup();
  std::array<std::shared_ptr<UdpPeer>, kSenders> peers_;
  sim4cv::proto::Envelope request_, reply_;
  std::vector<sim4cv::proto::Envelope> offered_;
  std::string reply_bytes_;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  sim4cv::fuzz::SharedHarness();  // built, and the logs quieted, before the peers below log
  Daemon daemon;
  for (std::string_view record : sim4cv::fuzz::SplitRecords(data, size)) {
    if (record.empty()) continue;
    const auto* bytes = reinterpret_cast<const uint8_t*>(record.data());
    daemon.Receive(bytes[0] % kSenders, bytes + 1, record.size() - 1);
    sim4cv::fuzz::SharedHarness().DrainCommands();
    daemon.SendOffered();
  }
  sim4cv::fuzz::SharedHarness().DrainCommands();
  return 0;
}
