// The UDP link: sim4cv::UdpClient (datagrams, sequence numbers, keep-alives,
// frames reassembled from chunks) under sim4cv::Client, which re-sends
// requests every retry interval until their answer comes.
#include "../link.h"
#include "sim4cv/udp_client.h"

namespace sim4cv::detail {
namespace {

class UdpLink : public Link {
 public:
  UdpLink(const std::string& host, uint16_t port)
      : host_(host), port_(port), address_("udp://" + host + ":" + std::to_string(port)) {
    udp_.Open(host, port);
  }

  const std::string& address() const override { return address_; }

  proto::Welcome Hello(const std::string& client_name, uint32_t protocol_version, Deadline deadline) override {
    udp_.Connect(host_, port_, client_name, Until(deadline), protocol_version);
    return udp_.welcome();
  }

  void Send(const proto::Envelope& envelope) override { udp_.SendEnvelope(envelope); }
  void SendRaw(const void* data, std::size_t size) override { udp_.SendRaw(data, size); }
  bool Receive(proto::Envelope& out, Deadline deadline, bool /*frame_wanted*/) override {
    return udp_.ReceiveEnvelope(out, Until(deadline));
  }
  std::chrono::milliseconds retry_interval() const override { return udp_.retry_interval(); }
  bool open() const override { return udp_.connected(); }
  void Close() override { udp_.Close(); }
  UdpClient* udp() override { return &udp_; }

 private:
  std::string host_;
  uint16_t port_;
  std::string address_;
  UdpClient udp_;
};

}  // namespace

std::unique_ptr<Link> OpenUdpLink(const std::string& host, uint16_t port) {
  return std::make_unique<UdpLink>(host, port);
}

}  // namespace sim4cv::detail
