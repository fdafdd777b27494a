// Unit tests of a client's area, daemon side (ShmClientArea): requests
// written as docs/protocol.md 13.5 says (by hand here, as a client in another
// language would) come out in order; a client that breaks the ring's rules is
// told so and nothing it wrote is followed; responses carry the documented
// sequence words and never depend on what the client stored; a response too
// long for the ring goes on the client's socket, tagged, and the ring says so.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>
#include <string>

#include "protocol/shm_sync.h"
#include "server/transport/shm/shm_client_area.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::transport {
namespace {

// "m<round>-<i>" (appended piece by piece: GCC 12 warns falsely on a chain of +).
std::string Label(int round, uint32_t i) {
  std::string label = "m";
  label += std::to_string(round);
  label += '-';
  label += std::to_string(i);
  return label;
}

// A connected pair of SOCK_SEQPACKET sockets: the attachment's, daemon end first.
struct SocketPair {
  SocketPair() { EXPECT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds), 0); }
  ~SocketPair() {
    close(fds[0]);
    close(fds[1]);
  }
  int fds[2] = {-1, -1};
};

class ShmRequestTest : public ::testing::Test {
 protected:
  // What a client does: write the slot, then a plain release store of the count.
  void Send(const std::string& bytes) {
    shm::ShmRequestSlot& slot = map().request(written_);
    slot.size = static_cast<uint32_t>(bytes.size());
    std::memcpy(slot.data, bytes.data(), bytes.size());
    shm::Atomic(map().header().request_write).store(++written_, std::memory_order_release);
  }
  ShmClientArea::Take Next(std::string& out) {
    const uint8_t* data = nullptr;
    uint32_t size = 0;
    why_.clear();
    const auto take = area_.Next(data, size, why_);
    if (take == ShmClientArea::Take::kMessage) out.assign(reinterpret_cast<const char*>(data), size);
    return take;
  }
  const shm::AreaMap& map() { return area_.map(); }

  SocketPair sockets_;
  ShmClientArea area_{sockets_.fds[0]};
  uint64_t written_ = 0;
  std::string why_;
};

TEST_F(ShmRequestTest, RequestsArriveInOrderAndFreeTheirSlots) {
  std::string got;
  EXPECT_EQ(Next(got), ShmClientArea::Take::kEmpty);
  for (int round = 0; round < 3; ++round) {  // past the end of the ring, twice
    for (uint32_t i = 0; i < shm::kShmRequestCapacity; ++i) Send(Label(round, i));
    for (uint32_t i = 0; i < shm::kShmRequestCapacity; ++i) {
      ASSERT_EQ(Next(got), ShmClientArea::Take::kMessage);
      EXPECT_EQ(got, Label(round, i));
    }
    EXPECT_EQ(Next(got), ShmClientArea::Take::kEmpty);
    EXPECT_EQ(map().header().request_read, written_);
  }
}

TEST_F(ShmRequestTest, CountsOutsideTheRingAreRefusedNotFollowed) {
  std::string got;
  Send("ok");
  ASSERT_EQ(Next(got), ShmClientArea::Take::kMessage);
  for (const uint64_t bad : {uint64_t{0}, uint64_t{1} + shm::kShmRequestCapacity + 1, UINT64_MAX, uint64_t{1} << 63}) {
    map().header().request_write = bad;
    EXPECT_EQ(Next(got), ShmClientArea::Take::kBroken) << bad;
    EXPECT_NE(why_.find("request_write (" + std::to_string(bad) + ")"), std::string::npos) << why_;
  }
  // Exactly a full ring is allowed.
  map().header().request_write = 1 + shm::kShmRequestCapacity;
  EXPECT_EQ(Next(got), ShmClientArea::Take::kMessage);
}

TEST_F(ShmRequestTest, OversizedRequestIsRefused) {
  std::string got;
  Send("x");
  map().request(0).size = 0xffffffffu;
  EXPECT_EQ(Next(got), ShmClientArea::Take::kBroken);
  EXPECT_NE(why_.find("4294967295 bytes"), std::string::npos) << why_;
  map().request(0).size = shm::kShmRequestDataBytes;  // the largest that fits
  EXPECT_EQ(Next(got), ShmClientArea::Take::kMessage);
  EXPECT_EQ(got.size(), shm::kShmRequestDataBytes);
}

TEST_F(ShmRequestTest, ResponsesUseTheDaemonsOwnCounts) {
  // The client scribbles over everything the daemon writes; the daemon reads none of it back.
  map().header().responses_written = 12345;
  map().response(0).sequence = 77;
  map().header().response_futex = 9;
  for (uint64_t k = 0; k < 10; ++k) {
    proto::Envelope reply;
    reply.mutable_state()->set_frame_id(k);
    ASSERT_EQ(area_.Write(reply), ShmClientArea::Written::kDone);
    const shm::ShmResponseMessage& message = map().response(k);
    EXPECT_EQ(message.sequence, shm::ResponseCompleteSequence(k));
    proto::Envelope parsed;
    ASSERT_TRUE(parsed.ParseFromArray(message.data, static_cast<int>(message.size)));
    EXPECT_EQ(parsed.state().frame_id(), k);
    EXPECT_EQ(map().header().responses_written, k + 1);
    EXPECT_EQ(map().header().response_futex, k + 1);
  }
  proto::Envelope huge;
  huge.mutable_error()->set_message(std::string(shm::kShmSocketResponseBytes, 'x'));
  EXPECT_EQ(area_.Write(huge), ShmClientArea::Written::kTooLarge);
  EXPECT_EQ(map().header().responses_written, 10u);
  area_.MarkClosed();
  EXPECT_EQ(map().header().closed, 1u);
}

TEST_F(ShmRequestTest, ALongResponseIsTheNextSocketMessageTaggedWithItsNumber) {
  proto::Envelope small, long_reply;
  small.mutable_state()->set_frame_id(7);
  long_reply.mutable_error()->set_message(std::string(5 * shm::kShmResponseDataBytes, 'x'));
  ASSERT_EQ(area_.Write(small), ShmClientArea::Written::kDone);
  ASSERT_EQ(area_.Write(long_reply), ShmClientArea::Written::kDone);
  const shm::ShmResponseMessage& message = map().response(1);
  EXPECT_EQ(message.sequence, shm::ResponseCompleteSequence(1));
  EXPECT_EQ(message.on_socket, 1u);
  EXPECT_EQ(message.size, long_reply.ByteSizeLong());
  EXPECT_EQ(map().response(0).on_socket, 0u);
  std::string received(shm::kShmSocketResponseHeaderBytes + shm::kShmSocketResponseBytes, '\0');
  const ssize_t got = recv(sockets_.fds[1], received.data(), received.size(), MSG_DONTWAIT);
  ASSERT_EQ(got, static_cast<ssize_t>(shm::kShmSocketResponseHeaderBytes + long_reply.ByteSizeLong()));
  uint64_t tag = 99;
  std::memcpy(&tag, received.data(), sizeof tag);
  EXPECT_EQ(tag, 1u);
  proto::Envelope parsed;
  ASSERT_TRUE(parsed.ParseFromArray(received.data() + shm::kShmSocketResponseHeaderBytes,
                                    static_cast<int>(got) - static_cast<int>(shm::kShmSocketResponseHeaderBytes)));
  EXPECT_EQ(parsed.error().message(), long_reply.error().message());
}

TEST_F(ShmRequestTest, ALongResponseThatFindsTheSocketFullIsNotWritten) {
  proto::Envelope long_reply;
  long_reply.mutable_error()->set_message(std::string(shm::kShmSocketResponseBytes - 16, 'x'));
  uint64_t written = 0;
  while (area_.Write(long_reply) == ShmClientArea::Written::kDone) {
    ASSERT_LT(++written, 100u) << "the socket never filled";
  }
  EXPECT_EQ(map().header().responses_written, written) << "a refused response takes no ring entry";
}

}  // namespace
}  // namespace sim4cv::transport
