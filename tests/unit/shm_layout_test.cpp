// Unit tests of the shared-memory layout (protocol/shm_layout.h, shm_sync.h)
// and of what the daemon creates (server/transport/shm/shm_region.*,
// shm_client_area.*): the offsets docs/protocol.md section 13 documents, the
// geometry rules, the seals, and the errors a client gives for a name nobody
// serves, a foreign answer, or another layout version.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstddef>
#include <cstring>
#include <string>
#include <thread>

#include "protocol/shm_sync.h"
#include "server/transport/shm/shm_client_area.h"
#include "server/transport/shm/shm_listener.h"
#include "server/transport/shm/shm_region.h"
#include "sim4cv/shm_client.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::shm {
namespace {

// Compile-time checks: the documented offsets (the header asserts more).
static_assert(offsetof(ShmHeader, magic) == 0 && offsetof(ShmHeader, layout_version) == 8);
static_assert(offsetof(ShmHeader, slot_count) == 24 && offsetof(ShmHeader, slot_bytes) == 32);
static_assert(offsetof(ShmHeader, camera_width) == 48 && offsetof(ShmHeader, writer_pid) == 56);
static_assert(offsetof(ShmHeader, expiry_ms) == 136 && offsetof(ShmHeader, protocol_version) == 140);
static_assert(offsetof(ShmHeader, channel_mask) == 152 && channels::kAllPixels == 0x1ee);
static_assert(offsetof(ShmHeader, newest_frame_id) == 200 && offsetof(ShmHeader, closed) == 216);
static_assert(offsetof(ShmFrameHeader, publication) == 8 && offsetof(ShmFrameHeader, frame_id) == 16);
static_assert(offsetof(ShmFrameHeader, render_end_mono_ns) == 32 && offsetof(ShmFrameHeader, channel_mask) == 48);
static_assert(offsetof(ShmFrameHeader, box_count) == 56 && offsetof(ShmFrameHeader, entity_count) == 64);
static_assert(offsetof(ShmAreaHeader, total_bytes) == 16 && offsetof(ShmAreaHeader, request_offset) == 24);
static_assert(offsetof(ShmAreaHeader, request_capacity) == 32 && offsetof(ShmAreaHeader, response_offset) == 40);
static_assert(offsetof(ShmAreaHeader, response_depth) == 48 && offsetof(ShmAreaHeader, responses_written) == 136);
static_assert(offsetof(ShmRequestSlot, size) == 0 && offsetof(ShmResponseMessage, size) == 8);
static_assert(offsetof(ShmAttach, status) == 12 && offsetof(ShmAttach, frames_bytes) == 16);
// Every field two processes touch concurrently is naturally aligned for atomics.
static_assert(offsetof(ShmHeader, published) % 8 == 0 && offsetof(ShmHeader, frame_futex) % 4 == 0);
static_assert(offsetof(ShmAreaHeader, request_write) % 8 == 0 && offsetof(ShmAreaHeader, request_read) % 8 == 0);
static_assert(offsetof(ShmAreaHeader, response_futex) % 4 == 0);

constexpr uint32_t kRgb = 0, kDepth = 1, kMask = 2, kSemantic = 3, kNormals = 4, kFlow = 5;  // plane indices
constexpr channels::ChannelSet kThree = channels::Bit(proto::CHANNEL_RGB) | channels::Bit(proto::CHANNEL_DEPTH) |
                                        channels::Bit(proto::CHANNEL_MASK);
static_assert(channels::IndexOf(proto::CHANNEL_FLOW) == kFlow && channels::IndexOf(proto::CHANNEL_SEMANTIC) == kSemantic);

TEST(ShmLayout, GeometryAlignsSlotsAndPlanes) {
  for (auto [w, h] : {std::pair{320u, 180u}, {17u, 19u}, {1280u, 720u}, {16u, 16u}}) {
    const Geometry g = ComputeGeometry(w, h, 8);
    const uint64_t pixels = static_cast<uint64_t>(w) * h;
    EXPECT_EQ(g.offsets[kRgb], kShmFrameHeaderBytes);
    for (std::size_t i = 1; i < channels::kPixelChannelCount; ++i) {
      EXPECT_EQ(g.offsets[i] % kShmAlignment, 0u);
      EXPECT_GE(g.offsets[i], g.offsets[i - 1] + pixels * channels::kPixelChannels[i - 1].bytes_per_pixel);
    }
    EXPECT_GE(g.slot_bytes, g.offsets[kFlow] + pixels * 8);
    EXPECT_EQ(g.slot_bytes % 4096, 0u);
    EXPECT_EQ(g.slots_offset, 4096u);
    EXPECT_EQ(g.total_bytes, g.slots_offset + 8 * g.slot_bytes);
  }
  // The figures docs/protocol.md quotes: the default --shm-channels, and all seven.
  EXPECT_EQ(ComputeGeometry(320, 180, 8, kThree).slot_bytes, 528384u);
  EXPECT_EQ(ComputeGeometry(320, 180, 8, kThree).total_bytes, 4231168u);
  EXPECT_EQ(ComputeGeometry(320, 180, 8).slot_bytes, 1912832u);
  EXPECT_EQ(kAreaRequestOffset, 256u);
  EXPECT_EQ(kAreaResponseOffset, 16640u);
  EXPECT_EQ(kAreaBytes, 36864u);
}

TEST(ShmLayout, SlotsHoldOnlyTheRingsChannels) {
  constexpr uint64_t kPixels = 320 * 180;
  // RGB alone: the figures docs/protocol.md quotes for --shm-channels rgb.
  const Geometry rgb = ComputeGeometry(320, 180, 8, channels::Bit(proto::CHANNEL_RGB));
  EXPECT_EQ(rgb.offsets[kRgb], kShmFrameHeaderBytes);
  for (std::size_t i = 1; i < channels::kPixelChannelCount; ++i) EXPECT_EQ(rgb.offsets[i], 0u);
  EXPECT_EQ(rgb.slot_bytes, 184320u);
  EXPECT_EQ(rgb.total_bytes, 4096u + 8 * 184320u);
  // Present planes are packed in table order from the slot header on.
  const Geometry depth_mask =
      ComputeGeometry(320, 180, 8, channels::Bit(proto::CHANNEL_DEPTH) | channels::Bit(proto::CHANNEL_MASK));
  EXPECT_EQ(depth_mask.offsets[kRgb], 0u);
  EXPECT_EQ(depth_mask.offsets[kDepth], kShmFrameHeaderBytes);
  EXPECT_EQ(depth_mask.offsets[kMask], AlignUp(kShmFrameHeaderBytes + kPixels * 4, kShmAlignment));
  EXPECT_EQ(depth_mask.slot_bytes, AlignUp(depth_mask.offsets[kMask] + kPixels * 2, 4096));
  const Geometry odd =
      ComputeGeometry(17, 19, 2, channels::Bit(proto::CHANNEL_RGB) | channels::Bit(proto::CHANNEL_NORMALS));
  EXPECT_EQ(odd.offsets[kNormals], AlignUp(kShmFrameHeaderBytes + 17 * 19 * 3, kShmAlignment));
  EXPECT_EQ(odd.slot_bytes, AlignUp(odd.offsets[kNormals] + 17 * 19 * 12, 4096));
  EXPECT_EQ(channels::Names(kThree), "rgb,depth,mask");
  EXPECT_EQ(channels::Names(channels::kAllPixels), "rgb,depth,mask,semantic,normals,flow,albedo");
}

TEST(ShmLayout, SocketPathIsAbstractAndBounded) {
  EXPECT_EQ(SocketPath("/x"), std::string("\0sim4cv-shm/x", 13));
  EXPECT_EQ(SocketPath(std::string(kShmMaxNameBytes, 'n')).size(), sizeof(sockaddr_un::sun_path));
}

transport::ShmRegionParams Params() {
  transport::ShmRegionParams p;
  p.camera_name = "uav";
  p.width = 40;
  p.height = 30;
  p.slot_count = 3;
  p.expiry_ms = 1234;
  return p;
}

TEST(ShmLayout, DaemonWritesTheDocumentedHeaderAndSealsTheObject) {
  transport::ShmRegion region(Params());
  const ShmHeader& h = region.header();
  EXPECT_EQ(std::string(h.magic, 8), "SIM4CVSM");
  EXPECT_EQ(h.layout_version, 4u);
  EXPECT_EQ(h.header_bytes, 512u);
  EXPECT_EQ(h.slot_count, 3u);
  EXPECT_EQ(h.camera_width, 40u);
  EXPECT_EQ(h.camera_height, 30u);
  EXPECT_EQ(h.writer_pid, static_cast<uint32_t>(getpid()));
  EXPECT_STREQ(h.camera_name, "uav");
  EXPECT_EQ(h.expiry_ms, 1234u);
  EXPECT_EQ(h.protocol_version, 1u);
  EXPECT_EQ(h.published, 0u);
  EXPECT_EQ(h.total_bytes, region.geometry().total_bytes);
  EXPECT_EQ(h.channel_mask, transport::kShmDefaultChannels);
  EXPECT_EQ(fcntl(region.fd(), F_GET_SEALS),
            F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_FUTURE_WRITE | F_SEAL_SEAL);

  ShmClient client;
  client.OpenFrames(region.fd());
  EXPECT_EQ(client.camera(), "uav");
  EXPECT_EQ(client.newest_frame_id(), 0u);
  OwnedFrame frame;
  EXPECT_FALSE(client.ReadNewest(frame));
  EXPECT_TRUE(client.carries(proto::CHANNEL_RGB) && client.carries(proto::CHANNEL_DEPTH) &&
              client.carries(proto::CHANNEL_MASK));
  EXPECT_FALSE(client.carries(proto::CHANNEL_BOXES)) << "boxes are not a pixel channel";
  EXPECT_THROW(client.Step(), ConnectionError) << "a frames-only reader has no request ring";
}

TEST(ShmLayout, ClientAreaIsSealedAgainstResizingOnly) {
  int sockets[2] = {-1, -1};
  ASSERT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET, 0, sockets), 0);
  transport::ShmClientArea area(sockets[0]);
  EXPECT_EQ(fcntl(area.fd(), F_GET_SEALS), F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_SEAL);
  const ShmAreaHeader& h = area.map().header();
  EXPECT_EQ(std::string(h.magic, 8), "SIM4CVCA");
  EXPECT_EQ(h.total_bytes, kAreaBytes);
  EXPECT_EQ(h.request_capacity, 64u);
  EXPECT_EQ(h.response_depth, 8u);
  close(sockets[0]);
  close(sockets[1]);
}

TEST(ShmLayout, RgbOnlyRingIsSmallerAndSaysWhatItCarries) {
  auto params = Params();
  params.channel_mask = channels::Bit(proto::CHANNEL_RGB);
  transport::ShmRegion region(params);
  EXPECT_EQ(region.header().channel_mask, 0x02u);
  EXPECT_EQ(region.header().slot_bytes, AlignUp(kShmFrameHeaderBytes + 40 * 30 * 3, 4096));
  ShmClient client;
  client.OpenFrames(region.fd());
  EXPECT_TRUE(client.carries(proto::CHANNEL_RGB));
  EXPECT_FALSE(client.carries(proto::CHANNEL_DEPTH));
  EXPECT_FALSE(client.carries(proto::CHANNEL_MASK));
}

void ExpectOpenFramesFails(const transport::ShmRegion& region, std::initializer_list<std::string> fragments) {
  ShmClient client;
  try {
    client.OpenFrames(region.fd());
    ADD_FAILURE() << "OpenFrames succeeded";
  } catch (const ShmError& error) {
    for (const auto& fragment : fragments)
      EXPECT_NE(std::string(error.what()).find(fragment), std::string::npos) << error.what();
  }
  EXPECT_FALSE(client.is_open());
}

TEST(ShmLayout, WrongLayoutVersionIsAClearError) {
  transport::ShmRegion region(Params());
  region.header().layout_version = 99;
  ExpectOpenFramesFails(region, {"layout version 99", "layout version 4"});
}

TEST(ShmLayout, InconsistentHeaderIsAClearError) {
  transport::ShmRegion region(Params());
  region.header().channel_mask = 0x1e;  // BOXES is no pixel channel
  ExpectOpenFramesFails(region, {"channel mask 30", "not a set of rgb,depth,mask,semantic,normals,flow"});
  region.header().channel_mask = channels::kAllPixels;
  region.header().slot_count = 1000;  // slots beyond the object
  ExpectOpenFramesFails(region, {"do not fit"});
}

std::string UniqueName(const char* what) { return "/sim4cv-unit-" + std::string(what) + "-" + std::to_string(getpid()); }

void ExpectOpenFails(const std::string& name, std::initializer_list<std::string> fragments) {
  ShmClient client;
  try {
    client.Open(name);
    ADD_FAILURE() << "Open(" << name << ") succeeded";
  } catch (const ShmError& error) {
    for (const auto& fragment : fragments)
      EXPECT_NE(std::string(error.what()).find(fragment), std::string::npos) << error.what();
  }
  EXPECT_FALSE(client.is_open());
}

TEST(ShmLayout, NameNobodyServesIsAClearError) {
  ExpectOpenFails(UniqueName("missing"), {"no sim4cvd serves shared memory under", "--shm-name"});
}

// A listener that answers one connection with `attach` (no descriptors).
void AnswerOnce(const std::string& name, const ShmAttach& attach, std::size_t bytes) {
  transport::ShmListener listener(name);
  std::thread client([&] { ExpectOpenFails(name, {name}); });
  int connection = -1;
  while ((connection = listener.Accept()) < 0) std::this_thread::yield();
  send(connection, &attach, bytes, MSG_NOSIGNAL);
  client.join();
  close(connection);
}

TEST(ShmLayout, ForeignOrOtherVersionAnswerIsAClearError) {
  ShmAttach attach{};
  std::memcpy(attach.magic, "GARBAGE!", 8);
  AnswerOnce(UniqueName("foreign"), attach, sizeof attach);
  std::memcpy(attach.magic, SIM4CV_SHM_ATTACH_MAGIC, 8);
  attach.layout_version = 1;
  AnswerOnce(UniqueName("old"), attach, sizeof attach);
  ExpectOpenFails(UniqueName("gone"), {"no sim4cvd serves"});
}

TEST(ShmLayout, RefusalReachesTheClientWithItsReason) {
  const std::string name = UniqueName("refuses");
  transport::ShmListener listener(name);
  std::thread client([&] { ExpectOpenFails(name, {"all 3 places taken"}); });
  int connection = -1;
  while ((connection = listener.Accept()) < 0) std::this_thread::yield();
  transport::ShmListener::Refuse(connection, "all 3 places taken");
  client.join();
  close(connection);
}

TEST(ShmLayout, BadParametersAreNamed) {
  EXPECT_THROW(transport::ShmListener("no-slash"), std::invalid_argument);
  EXPECT_THROW(transport::ShmListener("/" + std::string(kShmMaxNameBytes, 'n')), std::invalid_argument);
  {
    const std::string name = UniqueName("taken");
    transport::ShmListener first(name);
    try {
      transport::ShmListener second(name);
      ADD_FAILURE() << "two listeners on one name";
    } catch (const std::runtime_error& error) {
      EXPECT_NE(std::string(error.what()).find("another sim4cvd serves this --shm-name"), std::string::npos)
          << error.what();
    }
  }
  auto params = Params();
  params.slot_count = 1;
  try {
    transport::ShmRegion region(params);
    ADD_FAILURE() << "one slot accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("--shm-slots 1"), std::string::npos) << error.what();
  }
  for (const uint32_t mask : {0u, 0x10u, 0x0fu}) {
    params = Params();
    params.channel_mask = mask;
    try {
      transport::ShmRegion region(params);
      ADD_FAILURE() << "channel mask " << mask << " accepted";
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find("--shm-channels"), std::string::npos) << error.what();
    }
  }
}

}  // namespace
}  // namespace sim4cv::shm
