// A transport in one file: one client at a time on a Unix SOCK_SEQPACKET
// socket, where the kernel keeps message boundaries, so each Envelope is one
// message with no length prefix. Everything a client session means comes
// from session::ClientSession; this file only moves bytes. Registered by one
// line, daemon::RegisterTransport({"seqpacket", demo::MakeSeqpacketTransport});
// the worked example of docs/architecture.md, "Extending sim4cv".
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <vector>

#include "server/daemon/transports.h"
#include "server/session/client_session.h"
#include "server/transport/frame_encoding.h"

namespace sim4cv::demo {
namespace {

// The sim thread's wake-up; shared with the session, which may outlive us.
struct EventFd {
  int fd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  ~EventFd() { ::close(fd); }
  void Notify() const {
    const uint64_t one = 1;
    [[maybe_unused]] const auto n = ::write(fd, &one, sizeof one);
  }
};

class SeqpacketTransport final : public transport::Transport {
 public:
  explicit SeqpacketTransport(std::string path) : path_(std::move(path)) {
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    if (path_.size() >= sizeof address.sun_path) throw std::invalid_argument("socket path too long: " + path_);
    std::memcpy(address.sun_path, path_.c_str(), path_.size());
    listener_ = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
    if (::bind(listener_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 || ::listen(listener_, 4) != 0) {
      throw std::runtime_error("cannot listen on " + path_ + ": " + std::strerror(errno));
    }
  }
  ~SeqpacketTransport() override {
    Stop();
    ::close(listener_);
    ::unlink(path_.c_str());
  }

  // No TransportKind of its own: a transport for real adds one to the proto.
  proto::TransportInfo info() const override {
    proto::TransportInfo info;
    info.set_address(path_);
    return info;
  }
  std::string listening_field() const override { return "seqpacket=" + path_; }
  void Start(const session::ServerContext& context) override {
    context_ = &context;
    thread_ = std::thread([this] { Run(); });
  }
  void Stop() override {
    if (!thread_.joinable()) return;
    stopping_ = true;
    wake_->Notify();
    thread_.join();
  }

 private:
  void Run() {
    while (!stopping_) {
      pollfd fds[] = {{wake_->fd, POLLIN, 0}, {listener_, POLLIN, 0}, {client_, POLLIN, 0}};
      ::poll(fds, client_ >= 0 ? 3 : 2, -1);
      uint64_t wakes;
      [[maybe_unused]] const auto n = ::read(wake_->fd, &wakes, sizeof wakes);
      if (fds[1].revents & POLLIN) Accept();
      if (client_ >= 0 && fds[2].revents != 0) Receive();
      if (session_) SendOffered();
    }
    CloseClient();
  }

  void Accept() {
    const int fd = ::accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) return;
    if (client_ >= 0) {  // one client at a time
      ::close(fd);
      return;
    }
    client_ = fd;
    session_ = session::ClientSession::Create(session::NewClientId(), *context_, [wake = wake_] { wake->Notify(); });
  }

  void Receive() {
    buffer_.resize(context_->max_message_bytes);
    const ssize_t size = ::recv(client_, buffer_.data(), buffer_.size(), MSG_TRUNC | MSG_DONTWAIT);
    if (size < 0 && errno == EAGAIN) return;
    proto::Envelope request, reply;
    if (size <= 0 || static_cast<std::size_t>(size) > buffer_.size() ||
        !request.ParseFromArray(buffer_.data(), static_cast<int>(size))) {
      return CloseClient();  // gone, or bytes that are no Envelope within the size limit
    }
    if (session_->Handle(request, reply) == session::ClientProtocol::Outcome::kNoReply) return;
    if (session::ClientProtocol::EndsConnection(reply)) session_->StopOffers();
    Send(reply);
    if (session::ClientProtocol::EndsConnection(reply)) CloseClient();
  }

  // The sim thread's replies first, then the frames, in the session's order.
  void SendOffered() {
    while (session_) {
      session_->TakeReplies(replies_);
      for (const proto::Envelope& reply : replies_) Send(reply);
      if (!session_) return;  // a send failed: the client is gone
      session::FrameRef frame = session_->NextFrame();
      if (!frame) return;
      encoder_.Encode(*frame, *session_, false);
      std::vector<iovec> parts;
      for (const transport::Segment& s : encoder_.segments()) parts.push_back({const_cast<uint8_t*>(s.data), s.size});
      msghdr message{};
      message.msg_iov = parts.data();
      message.msg_iovlen = parts.size();
      if (::sendmsg(client_, &message, MSG_NOSIGNAL) < 0) return CloseClient();
      session_->FrameDone();
    }
  }

  void Send(const proto::Envelope& envelope) {
    const std::string bytes = envelope.SerializeAsString();
    if (client_ >= 0 && ::send(client_, bytes.data(), bytes.size(), MSG_NOSIGNAL) < 0) CloseClient();
  }

  void CloseClient() {
    if (session_) session_->Close(true);
    session_.reset();
    if (client_ >= 0) ::close(client_);
    client_ = -1;
  }

  const std::string path_;
  int listener_ = -1;
  int client_ = -1;
  std::shared_ptr<EventFd> wake_ = std::make_shared<EventFd>();
  std::atomic<bool> stopping_{false};
  const session::ServerContext* context_ = nullptr;
  std::shared_ptr<session::ClientSession> session_;
  std::vector<char> buffer_;
  std::vector<proto::Envelope> replies_;
  transport::FrameEncoder encoder_;
  std::thread thread_;
};

}  // namespace

// No flag of its own (a transport for real adds its fields to Config and
// their flags): it listens at $SIM4CV_SEQPACKET_PATH when that is set.
std::unique_ptr<transport::Transport> MakeSeqpacketTransport(const daemon::Config&, const sim::Scene&) {
  const char* path = std::getenv("SIM4CV_SEQPACKET_PATH");
  if (path == nullptr) return nullptr;
  return std::make_unique<SeqpacketTransport>(path);
}

}  // namespace sim4cv::demo
