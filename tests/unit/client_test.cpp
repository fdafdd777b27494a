// sim4cv::Client against a scripted fake server on loopback: each test's
// server side runs on its own thread and speaks raw framed envelopes.
#include "sim4cv/client.h"

#include <arpa/inet.h>
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdlib>
#include <functional>
#include <future>
#include <new>
#include <thread>

#include "protocol/framing.h"

// Counts heap allocations and their bytes per thread, to prove the warm
// frame path has none and a lying length prefix costs little.
namespace {
thread_local std::size_t t_allocations = 0;
thread_local std::size_t t_allocated_bytes = 0;
}
void* operator new(std::size_t size) {
  ++t_allocations;
  t_allocated_bytes += size;
  if (void* memory = std::malloc(size == 0 ? 1 : size)) return memory;
  throw std::bad_alloc();
}
void operator delete(void* memory) noexcept { std::free(memory); }
void operator delete(void* memory, std::size_t) noexcept { std::free(memory); }

namespace sim4cv {
namespace {

using proto::Envelope;
using std::chrono::milliseconds;
constexpr int kServerWaitMs = 5000;  // bounds every blocking step of the fake server

// A one-shot signal between the test thread and the server script.
class Gate {
 public:
  void Open() { promise_.set_value(); }
  void Wait() { EXPECT_EQ(future_.wait_for(milliseconds(kServerWaitMs)), std::future_status::ready); }

 private:
  std::promise<void> promise_;
  std::shared_future<void> future_ = promise_.get_future().share();
};

std::string Framed(const Envelope& envelope) {
  const std::string body = envelope.SerializeAsString();
  std::string bytes(wire::kLengthPrefixBytes, '\0');
  wire::EncodeLengthPrefix(static_cast<uint32_t>(body.size()), reinterpret_cast<uint8_t*>(bytes.data()));
  return bytes + body;
}

// The server's end of the one accepted connection.
class Peer {
 public:
  explicit Peer(int fd) : fd_(fd) {
    // Without it, back-to-back small sends wait ~40 ms for a delayed ACK.
    const int no_delay = 1;
    setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &no_delay, sizeof no_delay);
  }
  ~Peer() { close(fd_); }

  // Reads exactly `size` bytes; fewer if the client closed or went quiet.
  std::string ReadBytes(std::size_t size) {
    std::string bytes;
    char chunk[4096];
    while (bytes.size() < size) {
      pollfd entry{fd_, POLLIN, 0};
      if (poll(&entry, 1, kServerWaitMs) <= 0) break;
      const ssize_t got = recv(fd_, chunk, std::min(sizeof chunk, size - bytes.size()), 0);
      if (got <= 0) break;
      bytes.append(chunk, static_cast<std::size_t>(got));
    }
    return bytes;
  }
  Envelope Receive() {
    const std::string prefix = ReadBytes(wire::kLengthPrefixBytes);
    Envelope envelope;
    if (prefix.size() != wire::kLengthPrefixBytes) {
      ADD_FAILURE() << "fake server: no envelope from the client";
      return envelope;
    }
    const uint32_t size = wire::DecodeLengthPrefix(reinterpret_cast<const uint8_t*>(prefix.data()));
    EXPECT_TRUE(envelope.ParseFromString(ReadBytes(size)));
    return envelope;
  }
  void SendBytes(const std::string& bytes) {
    ASSERT_EQ(send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL), static_cast<ssize_t>(bytes.size()));
  }
  void Send(const Envelope& envelope) { SendBytes(Framed(envelope)); }
  // True once the client closed its end without sending anything more.
  bool ClientClosed() { return ReadBytes(1).empty(); }

 private:
  int fd_;
};

// Listens on 127.0.0.1 (any port) and runs `script` on the first connection.
class FakeServer {
 public:
  explicit FakeServer(std::function<void(Peer&)> script) {
    listen_fd_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof address;
    EXPECT_EQ(bind(listen_fd_, reinterpret_cast<sockaddr*>(&address), length), 0);
    EXPECT_EQ(listen(listen_fd_, 1), 0);
    EXPECT_EQ(getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&address), &length), 0);
    port_ = ntohs(address.sin_port);
    thread_ = std::thread([this, script = std::move(script)] {
      pollfd entry{listen_fd_, POLLIN, 0};
      if (poll(&entry, 1, kServerWaitMs) <= 0) return;
      Peer peer(accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC));
      script(peer);
    });
  }
  ~FakeServer() {
    thread_.join();
    close(listen_fd_);
  }
  uint16_t port() const { return port_; }

 private:
  int listen_fd_ = -1;
  uint16_t port_ = 0;
  std::thread thread_;
};

Envelope MakeWelcome() {
  Envelope envelope;
  proto::Welcome& welcome = *envelope.mutable_welcome();
  welcome.set_protocol_version(wire::kProtocolVersion);
  welcome.set_scene_name("default");
  welcome.set_mode(proto::SIM_MODE_LOCKSTEP);
  welcome.set_client_id(7);
  proto::CameraInfo& camera = *welcome.add_cameras();
  camera.set_name("uav");
  camera.set_width(32);
  camera.set_height(18);
  return envelope;
}

Envelope MakeFrame(uint64_t frame_id, uint32_t width = 32, uint32_t height = 18) {
  Envelope envelope;
  proto::Frame& frame = *envelope.mutable_frame();
  frame.set_frame_id(frame_id);
  frame.set_camera("uav");
  frame.set_width(width);
  frame.set_height(height);
  proto::Image& rgb = *frame.add_images();
  rgb.set_channel(proto::CHANNEL_RGB);
  rgb.set_format(proto::PIXEL_FORMAT_RGB8);
  rgb.set_stride(3 * width);
  rgb.set_data(std::string(3 * width * height, static_cast<char>(frame_id)));
  proto::Image& mask = *frame.add_images();
  mask.set_channel(proto::CHANNEL_MASK);
  mask.set_format(proto::PIXEL_FORMAT_INSTANCE_U16);
  mask.set_stride(2 * width);
  mask.set_data(std::string(2 * width * height, '\1'));
  proto::Box& box = *frame.add_boxes();
  box.set_object_id(1);
  box.set_width(4);
  box.set_height(3);
  box.set_visibility(0.5f);
  return envelope;
}

Envelope MakeError(proto::ErrorCode code, const std::string& message, bool fatal) {
  Envelope envelope;
  envelope.mutable_error()->set_code(code);
  envelope.mutable_error()->set_message(message);
  envelope.mutable_error()->set_fatal(fatal);
  return envelope;
}

Envelope MakeState(uint64_t frame_id) {
  Envelope envelope;
  envelope.mutable_state()->set_frame_id(frame_id);
  return envelope;
}

Envelope MakeSubscribed() {
  Envelope envelope;
  envelope.mutable_subscribed()->set_camera("uav");
  return envelope;
}

// Answers the Hello with a Welcome, as every script but the handshake tests does.
void Handshake(Peer& peer) {
  EXPECT_TRUE(peer.Receive().has_hello());
  peer.Send(MakeWelcome());
}

bool SameMessage(const google::protobuf::Message& a, const google::protobuf::Message& b) {
  return google::protobuf::util::MessageDifferencer::Equals(a, b);
}

TEST(ClientTest, ConnectSendsHelloAndKeepsWelcome) {
  FakeServer server([](Peer& peer) {
    const Envelope hello = peer.Receive();
    EXPECT_EQ(hello.hello().protocol_version(), wire::kProtocolVersion);
    EXPECT_EQ(hello.hello().client_name(), "unit-test");
    peer.Send(MakeWelcome());
  });
  Client client;
  client.Connect("127.0.0.1", server.port(), "unit-test");
  EXPECT_TRUE(client.connected());
  EXPECT_TRUE(SameMessage(client.welcome(), MakeWelcome().welcome()));
}

TEST(ClientTest, VersionMismatchIsFatalServerError) {
  FakeServer server([](Peer& peer) {
    EXPECT_EQ(peer.Receive().hello().protocol_version(), 99u);
    peer.Send(MakeError(proto::ERROR_CODE_VERSION_MISMATCH, "client speaks 99, server 1", true));
    EXPECT_TRUE(peer.ClientClosed());
  });
  Client client;
  try {
    client.Connect("127.0.0.1", server.port(), "old", milliseconds(5000), 99);
    FAIL() << "Connect accepted a refused Hello";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_VERSION_MISMATCH);
    EXPECT_STREQ(error.what(), "client speaks 99, server 1");
    EXPECT_TRUE(error.fatal());
  }
  EXPECT_FALSE(client.connected());
}

TEST(ClientTest, SilentServerTimesOutConnect) {
  Gate client_done;
  FakeServer server([&](Peer&) { client_done.Wait(); });
  Client client;
  EXPECT_THROW(client.Connect("127.0.0.1", server.port(), "c", milliseconds(50)), ConnectionError);
  EXPECT_FALSE(client.connected());
  client_done.Open();
}

TEST(ClientTest, RefusedConnectionNamesHostAndPort) {
  // Bound but not listening: connecting is refused.
  const int bound = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  ASSERT_EQ(bind(bound, reinterpret_cast<sockaddr*>(&address), length), 0);
  ASSERT_EQ(getsockname(bound, reinterpret_cast<sockaddr*>(&address), &length), 0);
  const std::string endpoint = "127.0.0.1:" + std::to_string(ntohs(address.sin_port));
  Client client;
  try {
    client.Connect("127.0.0.1", ntohs(address.sin_port));
    FAIL() << "connected to a port nobody listens on";
  } catch (const ConnectionError& error) {
    EXPECT_NE(std::string(error.what()).find(endpoint), std::string::npos) << error.what();
  }
  close(bound);
}

TEST(ClientTest, EnvelopesRoundTripWithLittleEndianPrefix) {
  FakeServer server([](Peer& peer) {
    Handshake(peer);
    Envelope controls;
    proto::Controls& expected = *controls.mutable_controls();
    expected.set_entity_id(1);
    expected.set_steering(-0.5f);
    expected.set_throttle(0.25f);
    const std::string body = controls.SerializeAsString();
    ASSERT_LT(body.size(), 256u);
    EXPECT_EQ(peer.ReadBytes(4), std::string({static_cast<char>(body.size()), 0, 0, 0}));
    EXPECT_EQ(peer.ReadBytes(body.size()), body);
    const Envelope output = peer.Receive();
    EXPECT_EQ(output.tracker_output().frame_id(), 3u);
    EXPECT_FLOAT_EQ(output.tracker_output().box().width(), 10.f);
    EXPECT_FLOAT_EQ(output.tracker_output().confidence(), 0.75f);
    EXPECT_TRUE(peer.Receive().has_step());
    peer.Send(MakeFrame(1));
  });
  Client client;
  client.Connect("127.0.0.1", server.port());
  client.SendControls(1, -0.5f, 0.25f, 0.f);
  client.SendTrackerOutput(3, 1.f, 2.f, 10.f, 5.f, 0.75f);
  EXPECT_TRUE(SameMessage(client.StepAndReceive(), MakeFrame(1).frame()));
}

TEST(ClientTest, NonFatalServerErrorKeepsTheConnection) {
  FakeServer server([](Peer& peer) {
    Handshake(peer);
    EXPECT_EQ(peer.Receive().subscribe().camera(), "nope");
    peer.Send(MakeError(proto::ERROR_CODE_UNKNOWN_CAMERA, "unknown camera 'nope'; cameras: uav", false));
    EXPECT_EQ(peer.Receive().subscribe().camera(), "uav");
    peer.Send(MakeSubscribed());
  });
  Client client;
  client.Connect("127.0.0.1", server.port());
  try {
    client.Subscribe("nope", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
    FAIL() << "Subscribe accepted a refusal";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_UNKNOWN_CAMERA);
    EXPECT_STREQ(error.what(), "unknown camera 'nope'; cameras: uav");
    EXPECT_FALSE(error.fatal());
  }
  EXPECT_TRUE(client.connected());
  client.Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
}

TEST(ClientTest, FatalServerErrorClosesTheConnection) {
  FakeServer server([](Peer& peer) {
    Handshake(peer);
    EXPECT_TRUE(peer.Receive().has_step());
    peer.Send(MakeError(proto::ERROR_CODE_MALFORMED_MESSAGE, "bad bytes", true));
    EXPECT_TRUE(peer.ClientClosed());
  });
  Client client;
  client.Connect("127.0.0.1", server.port());
  proto::Frame frame;
  client.Step();
  EXPECT_THROW(client.ReceiveFrame(frame), ServerError);
  EXPECT_FALSE(client.connected());
  EXPECT_THROW(client.ReceiveFrame(frame), ConnectionError);
}

TEST(ClientTest, TimeoutReturnsFalseAndAPartialFrameResumes) {
  Gate half_sent, client_timed_out;
  FakeServer server([&](Peer& peer) {
    Handshake(peer);
    const std::string bytes = Framed(MakeFrame(5));
    peer.SendBytes(bytes.substr(0, bytes.size() / 2));
    half_sent.Open();
    client_timed_out.Wait();
    peer.SendBytes(bytes.substr(bytes.size() / 2));
  });
  Client client;
  client.Connect("127.0.0.1", server.port());
  proto::Frame frame;
  half_sent.Wait();
  const auto start = std::chrono::steady_clock::now();
  EXPECT_FALSE(client.ReceiveFrame(frame, milliseconds(30)));
  EXPECT_GE(std::chrono::steady_clock::now() - start, milliseconds(30));
  client_timed_out.Open();
  ASSERT_TRUE(client.ReceiveFrame(frame));
  EXPECT_TRUE(SameMessage(frame, MakeFrame(5).frame()));
}

TEST(ClientTest, OversizePrefixIsConnectionError) {
  FakeServer server([](Peer& peer) {
    Handshake(peer);
    peer.SendBytes(std::string(4, '\xff'));
  });
  Client client;
  client.Connect("127.0.0.1", server.port());
  Envelope envelope;
  try {
    client.ReceiveEnvelope(envelope, milliseconds(5000));
    FAIL() << "accepted a 4 GiB prefix";
  } catch (const ConnectionError& error) {
    EXPECT_NE(std::string(error.what()).find("4294967295"), std::string::npos) << error.what();
  }
  EXPECT_FALSE(client.connected());
}

// A peer that announces a message of 64 MiB (within the client's limit) and
// sends a few bytes of it must not make the client allocate 64 MiB.
TEST(ClientTest, ALyingLengthPrefixAllocatesOnlyWhatArrives) {
  Gate sent, client_done;
  FakeServer server([&](Peer& peer) {
    Handshake(peer);
    const uint32_t announced = 64u << 20;
    std::string bytes(4, '\0');
    for (int i = 0; i < 4; ++i) bytes[i] = static_cast<char>(announced >> (8 * i));
    peer.SendBytes(bytes + std::string(100, '\x0a'));
    sent.Open();
    client_done.Wait();
  });
  Client client;
  client.Connect("127.0.0.1", server.port());
  client.set_max_message_bytes(64u << 20);
  sent.Wait();
  Envelope envelope;
  const std::size_t before = t_allocated_bytes;
  EXPECT_FALSE(client.ReceiveEnvelope(envelope, milliseconds(200)));
  EXPECT_LE(t_allocated_bytes - before, std::size_t{2} << 20) << "bytes allocated for 104 bytes received";
  client_done.Open();
}

TEST(ClientTest, StateArrivingWhileWaitingForAFrameIsKeptForGetState) {
  FakeServer server([](Peer& peer) {
    Handshake(peer);
    EXPECT_TRUE(peer.Receive().has_get_state());
    EXPECT_TRUE(peer.Receive().has_step());
    peer.Send(MakeState(4));
    peer.Send(MakeFrame(5));
    EXPECT_TRUE(peer.ClientClosed());  // GetState() must not ask a second time
  });
  Client client;
  client.Connect("127.0.0.1", server.port());
  Envelope get_state;
  get_state.mutable_get_state();
  client.SendEnvelope(get_state);
  EXPECT_EQ(client.StepAndReceive().frame_id(), 5u);
  EXPECT_EQ(client.GetState().frame_id(), 4u);
}

TEST(ClientTest, FramesArrivingWhileWaitingForStateKeepTheirOrder) {
  FakeServer server([](Peer& peer) {
    Handshake(peer);
    EXPECT_TRUE(peer.Receive().has_get_state());
    peer.Send(MakeFrame(1));
    peer.Send(MakeFrame(2));
    peer.Send(MakeState(2));
    EXPECT_TRUE(peer.ClientClosed());  // stay open: EOF would fail the client's reads
  });
  Client client;
  client.Connect("127.0.0.1", server.port());
  EXPECT_EQ(client.GetState().frame_id(), 2u);
  proto::Frame frame;
  ASSERT_TRUE(client.ReceiveFrame(frame, milliseconds(0)));
  EXPECT_EQ(frame.frame_id(), 1u);
  Envelope envelope;
  ASSERT_TRUE(client.ReceiveEnvelope(envelope, milliseconds(0)));
  EXPECT_EQ(envelope.frame().frame_id(), 2u);
  EXPECT_FALSE(client.ReceiveEnvelope(envelope, milliseconds(0)));
}

TEST(ClientTest, SubscribeDropsFramesOfThePreviousSubscription) {
  FakeServer server([](Peer& peer) {
    Handshake(peer);
    EXPECT_TRUE(peer.Receive().has_subscribe());
    peer.Send(MakeFrame(1));
    peer.Send(MakeSubscribed());
    EXPECT_TRUE(peer.ClientClosed());
  });
  Client client;
  client.Connect("127.0.0.1", server.port());
  client.Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_NEWEST);
  proto::Frame frame;
  EXPECT_FALSE(client.ReceiveFrame(frame, milliseconds(0)));
}

TEST(ClientTest, DeadServerIsConnectionErrorNotSigpipe) {
  FakeServer server([](Peer& peer) { Handshake(peer); });  // closes right after the Welcome
  Client client;
  client.Connect("127.0.0.1", server.port());
  // The first sends may still land in the socket buffer; the reset follows.
  EXPECT_THROW(
      for (int i = 0; i < 1000; ++i) {
        client.SendControls(1, 0.f, 0.f, 0.f);
        std::this_thread::sleep_for(milliseconds(1));
      },
      ConnectionError);
  EXPECT_FALSE(client.connected());
}

TEST(ClientTest, WarmReceiveFrameDoesNotAllocate) {
  constexpr int kFrames = 5;
  FakeServer server([](Peer& peer) {
    Handshake(peer);
    for (int i = 1; i <= kFrames; ++i) peer.Send(MakeFrame(i, 320, 180));
  });
  Client client;
  client.Connect("127.0.0.1", server.port());
  proto::Frame frame;
  // Two frames warm both buffers that take turns: the caller's and the client's.
  for (int i = 1; i <= 2; ++i) ASSERT_TRUE(client.ReceiveFrame(frame));
  for (int i = 3; i <= kFrames; ++i) {
    const std::size_t before = t_allocations;
    ASSERT_TRUE(client.ReceiveFrame(frame));
    EXPECT_EQ(t_allocations - before, 0u) << "frame " << i;
    EXPECT_EQ(frame.frame_id(), static_cast<uint64_t>(i));
  }
}

TEST(ClientTest, FindImageViewsTheChannelsBytes) {
  const proto::Frame frame = MakeFrame(1).frame();
  const auto mask = FindImage(frame, proto::CHANNEL_MASK);
  ASSERT_TRUE(mask.has_value());
  EXPECT_EQ(mask->data, reinterpret_cast<const uint8_t*>(frame.images(1).data().data()));
  EXPECT_EQ(mask->width, 32u);
  EXPECT_EQ(mask->height, 18u);
  EXPECT_EQ(mask->stride, 64u);
  EXPECT_EQ(mask->format, proto::PIXEL_FORMAT_INSTANCE_U16);
  EXPECT_FALSE(FindImage(frame, proto::CHANNEL_DEPTH).has_value());

  proto::Frame truncated = frame;
  truncated.mutable_images(0)->mutable_data()->resize(10);
  EXPECT_THROW(FindImage(truncated, proto::CHANNEL_RGB), ConnectionError);
}

}  // namespace
}  // namespace sim4cv
