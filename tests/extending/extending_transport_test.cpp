// A transport added as one file plus one registration line
// (seqpacket_transport.cpp): the daemon's own RunDaemon, in this process,
// serves it beside TCP, and a client on it says Hello, subscribes and steps
// a lockstep world through the session code every transport shares.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "protocol/framing.h"
#include "server/daemon/transports.h"
#include "tests/extending/in_process_daemon.h"

namespace sim4cv::demo {
std::unique_ptr<transport::Transport> MakeSeqpacketTransport(const daemon::Config&, const sim::Scene&);
}

namespace sim4cv {
namespace {

// One Envelope per message, as the transport sends them; fails the test after `seconds`.
proto::Envelope Receive(int fd, int seconds = 60) {
  timeval timeout{seconds, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  std::vector<char> buffer(1 << 20);
  const ssize_t size = ::recv(fd, buffer.data(), buffer.size(), 0);
  proto::Envelope envelope;
  EXPECT_GT(size, 0) << "no message within " << seconds << " s";
  if (size > 0) {
    EXPECT_TRUE(envelope.ParseFromArray(buffer.data(), static_cast<int>(size)));
  }
  return envelope;
}

void Send(int fd, const proto::Envelope& envelope) {
  const std::string bytes = envelope.SerializeAsString();
  ASSERT_EQ(::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL), static_cast<ssize_t>(bytes.size()));
}

TEST(ExtendingTransport, ARegisteredTransportServesAClientThroughTheRealDaemon) {
  daemon::RegisterTransport({"seqpacket", demo::MakeSeqpacketTransport});  // the one registration line

  const std::string socket_path =
      (std::filesystem::temp_directory_path() / ("sim4cv-seqpacket-" + std::to_string(::getpid()))).string();
  ::setenv("SIM4CV_SEQPACKET_PATH", socket_path.c_str(), 1);
  testing::InProcessDaemon daemon(
      {"--tcp-port", "0", "--udp-port", "-1", "--mode", "lockstep", "--width", "64", "--height", "48"});
  EXPECT_NE(daemon.listening_line().find(" seqpacket=" + socket_path), std::string::npos) << daemon.listening_line();

  const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::strncpy(address.sun_path, socket_path.c_str(), sizeof address.sun_path - 1);
  ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address), 0) << std::strerror(errno);

  proto::Envelope hello;
  hello.mutable_hello()->set_protocol_version(wire::kProtocolVersion);
  hello.mutable_hello()->set_client_name("seqpacket");
  hello.mutable_hello()->set_token(testing::InProcessDaemon::kToken);
  Send(fd, hello);
  const proto::Envelope welcome = Receive(fd);
  ASSERT_TRUE(welcome.has_welcome()) << welcome.ShortDebugString();
  ASSERT_EQ(welcome.welcome().transports_size(), 2);  // TCP, then the registered one
  EXPECT_EQ(welcome.welcome().transports(1).address(), socket_path);

  proto::Envelope subscribe;
  subscribe.mutable_subscribe()->set_camera("uav");
  subscribe.mutable_subscribe()->add_channels(proto::CHANNEL_RGB);
  subscribe.mutable_subscribe()->add_channels(proto::CHANNEL_DEPTH);
  subscribe.mutable_subscribe()->set_delivery(proto::DELIVERY_LOCKSTEP);
  Send(fd, subscribe);
  ASSERT_TRUE(Receive(fd).has_subscribed());
  uint64_t last_frame = 0;
  for (int step = 0; step < 3; ++step) {
    proto::Envelope request;
    request.mutable_step();
    Send(fd, request);
    const proto::Envelope frame = Receive(fd);
    ASSERT_TRUE(frame.has_frame()) << frame.ShortDebugString().substr(0, 300);
    EXPECT_GT(frame.frame().frame_id(), last_frame);
    last_frame = frame.frame().frame_id();
    ASSERT_EQ(frame.frame().images_size(), 2);
    EXPECT_EQ(frame.frame().images(0).data().size(), 64u * 48u * 3u);  // the pixels, framed by the shared encoder
    EXPECT_EQ(frame.frame().images(1).data().size(), 64u * 48u * 4u);
  }

  // A bad request gets the session's Error, as on every transport.
  proto::Envelope unknown_camera;
  unknown_camera.mutable_subscribe()->set_camera("nowhere");
  unknown_camera.mutable_subscribe()->add_channels(proto::CHANNEL_RGB);
  unknown_camera.mutable_subscribe()->set_delivery(proto::DELIVERY_LOCKSTEP);
  Send(fd, unknown_camera);
  const proto::Envelope error = Receive(fd);
  ASSERT_TRUE(error.has_error());
  EXPECT_NE(error.error().message().find("nowhere"), std::string::npos) << error.error().message();

  ::close(fd);
  EXPECT_EQ(daemon.Stop(), 0);
  EXPECT_FALSE(std::filesystem::exists(socket_path));  // the transport removed its socket when it stopped
}

}  // namespace
}  // namespace sim4cv
