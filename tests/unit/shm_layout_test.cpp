// Unit tests of the shared-memory layout (protocol/shm_layout.h, shm_sync.h)
// and of the header the daemon writes (server/transport/shm/shm_region.*):
// the offsets docs/protocol.md section 13 documents, the geometry rules, the
// reply checksum's test vectors, and the errors a client gives for an object
// that is missing, foreign, or of another layout version.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

#include "protocol/shm_sync.h"
#include "server/transport/shm/shm_region.h"
#include "sim4cv/shm_client.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::shm {
namespace {

// Compile-time checks: the documented offsets (the header asserts more).
static_assert(offsetof(ShmHeader, magic) == 0 && offsetof(ShmHeader, layout_version) == 8);
static_assert(offsetof(ShmHeader, slot_count) == 24 && offsetof(ShmHeader, slot_bytes) == 32);
static_assert(offsetof(ShmHeader, camera_width) == 48 && offsetof(ShmHeader, writer_pid) == 56);
static_assert(offsetof(ShmHeader, reply_offset) == 96 && offsetof(ShmHeader, reply_capacity) == 104);
static_assert(offsetof(ShmHeader, response_offset) == 112 && offsetof(ShmHeader, response_entries) == 120);
static_assert(offsetof(ShmHeader, expiry_ms) == 136 && offsetof(ShmHeader, protocol_version) == 140);
static_assert(offsetof(ShmHeader, channel_mask) == 152 && kShmAllPixelChannels == 0x0e);
static_assert(offsetof(ShmHeader, newest_frame_id) == 200 && offsetof(ShmHeader, frame_waiters) == 212);
static_assert(offsetof(ShmHeader, reply_sleeping) == 268 && offsetof(ShmHeader, replies_dropped) == 328);
static_assert(offsetof(ShmHeader, response_waiters) == 388);
static_assert(offsetof(ShmFrameHeader, publication) == 8 && offsetof(ShmFrameHeader, frame_id) == 16);
static_assert(offsetof(ShmFrameHeader, render_end_mono_ns) == 32 && offsetof(ShmFrameHeader, channel_mask) == 48);
static_assert(offsetof(ShmFrameHeader, box_count) == 56 && offsetof(ShmFrameHeader, entity_count) == 64);
static_assert(offsetof(ShmReplySlot, token) == 8 && offsetof(ShmReplySlot, size) == 16);
static_assert(offsetof(ShmReplySlot, checksum) == 20);
static_assert(offsetof(ShmResponseEntry, written) == 8 && offsetof(ShmResponseEntry, generation) == 16);
static_assert(offsetof(ShmResponseMessage, index) == 8 && offsetof(ShmResponseMessage, size) == 16);
// Every field the two sides touch concurrently is naturally aligned for atomics.
static_assert(offsetof(ShmHeader, published) % 8 == 0 && offsetof(ShmHeader, reply_write) % 8 == 0);
static_assert(offsetof(ShmHeader, frame_futex) % 4 == 0 && offsetof(ShmHeader, reply_futex) % 4 == 0);

TEST(ShmLayout, GeometryAlignsSlotsAndPlanes) {
  for (auto [w, h] : {std::pair{320u, 180u}, {17u, 19u}, {1280u, 720u}, {16u, 16u}}) {
    const Geometry g = ComputeGeometry(w, h, 8, 256, 64);
    const uint64_t pixels = static_cast<uint64_t>(w) * h;
    EXPECT_EQ(g.rgb_offset, kShmFrameHeaderBytes);
    EXPECT_EQ(g.depth_offset % kShmAlignment, 0u);
    EXPECT_EQ(g.mask_offset % kShmAlignment, 0u);
    EXPECT_GE(g.depth_offset, g.rgb_offset + pixels * 3);
    EXPECT_GE(g.mask_offset, g.depth_offset + pixels * 4);
    EXPECT_GE(g.slot_bytes, g.mask_offset + pixels * 2);
    EXPECT_EQ(g.slot_bytes % 4096, 0u);
    EXPECT_EQ(g.slots_offset, 4096u);
    EXPECT_EQ(g.reply_offset, g.slots_offset + 8 * g.slot_bytes);
    EXPECT_EQ(g.response_offset, g.reply_offset + 256u * kShmReplySlotBytes);
    EXPECT_EQ(g.response_entry_bytes, 64u + 8u * 2048u);
    EXPECT_EQ(g.total_bytes, AlignUp(g.response_offset + 64 * g.response_entry_bytes, 4096));
  }
  EXPECT_EQ(ComputeGeometry(320, 180, 8, 256, 64).slot_bytes, 528384u);  // the figure docs/protocol.md quotes
}

TEST(ShmLayout, SlotsHoldOnlyTheRingsChannels) {
  constexpr uint64_t kPixels = 320 * 180;
  // RGB alone: the figures docs/protocol.md quotes for --shm-channels rgb.
  const Geometry rgb = ComputeGeometry(320, 180, 8, 256, 64, ChannelBit(kShmChannelRgb));
  EXPECT_EQ(rgb.rgb_offset, kShmFrameHeaderBytes);
  EXPECT_EQ(rgb.depth_offset, 0u);
  EXPECT_EQ(rgb.mask_offset, 0u);
  EXPECT_EQ(rgb.slot_bytes, 184320u);
  EXPECT_EQ(rgb.reply_offset, 4096u + 8 * 184320u);
  // Present planes are packed in RGB, DEPTH, MASK order from the slot header on.
  const Geometry depth_mask =
      ComputeGeometry(320, 180, 8, 256, 64, ChannelBit(kShmChannelDepth) | ChannelBit(kShmChannelMask));
  EXPECT_EQ(depth_mask.rgb_offset, 0u);
  EXPECT_EQ(depth_mask.depth_offset, kShmFrameHeaderBytes);
  EXPECT_EQ(depth_mask.mask_offset, AlignUp(kShmFrameHeaderBytes + kPixels * 4, kShmAlignment));
  EXPECT_EQ(depth_mask.slot_bytes, AlignUp(depth_mask.mask_offset + kPixels * 2, 4096));
  const Geometry odd = ComputeGeometry(17, 19, 2, 8, 1, ChannelBit(kShmChannelRgb) | ChannelBit(kShmChannelMask));
  EXPECT_EQ(odd.mask_offset, AlignUp(kShmFrameHeaderBytes + 17 * 19 * 3, kShmAlignment));
  EXPECT_EQ(odd.mask_offset % kShmAlignment, 0u);
  // The default is every channel, as before the mask existed.
  EXPECT_EQ(ComputeGeometry(320, 180, 8, 256, 64, kShmAllPixelChannels).slot_bytes,
            ComputeGeometry(320, 180, 8, 256, 64).slot_bytes);
  EXPECT_EQ(ChannelFlagValue(kShmAllPixelChannels), "rgb,depth,mask");
  EXPECT_EQ(ChannelFlagValue(ChannelBit(kShmChannelMask)), "mask");
}

TEST(ShmLayout, ReplyChecksumTestVectors) {
  // Also quoted in docs/protocol.md for implementers in other languages.
  EXPECT_EQ(ReplyChecksum(1, nullptr, 0), 0x0eaff284u);
  const uint8_t step[2] = {0x2a, 0x00};
  EXPECT_EQ(ReplyChecksum(0x0123456789abcdefull, step, 2), 0x77f1b415u);
}

TEST(ShmLayout, ReplyStateEncoding) {
  EXPECT_EQ(ReplyWritingState(0), 1u);
  EXPECT_EQ(ReplyCompleteState(0), 2u);
  EXPECT_EQ(ReplyTicketOf(ReplyWritingState(41)), 41u);
  EXPECT_EQ(ReplyTicketOf(ReplyCompleteState(41)), 41u);
}

// Every name a test used is removed at exit, even after a failed assertion.
struct Names {
  std::vector<std::string> used;
  ~Names() {
    for (const auto& name : used) shm_unlink(name.c_str());
  }
};

std::string UniqueName(const char* what) {
  static Names names;
  names.used.push_back("/sim4cv-unit-" + std::string(what) + "-" + std::to_string(getpid()));
  return names.used.back();
}

transport::ShmRegionParams Params(const std::string& name) {
  transport::ShmRegionParams p;
  p.name = name;
  p.camera_name = "uav";
  p.width = 40;
  p.height = 30;
  p.slot_count = 3;
  p.reply_capacity = 16;
  p.response_entries = 4;
  p.expiry_ms = 1234;
  return p;
}

TEST(ShmLayout, DaemonWritesTheDocumentedHeader) {
  transport::ShmRegion region(Params(UniqueName("header")));
  const ShmHeader& h = region.header();
  EXPECT_EQ(std::string(h.magic, 8), "SIM4CVSM");
  EXPECT_EQ(h.layout_version, kShmLayoutVersion);
  EXPECT_EQ(h.header_bytes, 512u);
  EXPECT_EQ(h.slot_count, 3u);
  EXPECT_EQ(h.camera_width, 40u);
  EXPECT_EQ(h.camera_height, 30u);
  EXPECT_EQ(h.writer_pid, static_cast<uint32_t>(getpid()));
  EXPECT_STREQ(h.camera_name, "uav");
  EXPECT_EQ(h.reply_capacity, 16u);
  EXPECT_EQ(h.response_entries, 4u);
  EXPECT_EQ(h.expiry_ms, 1234u);
  EXPECT_EQ(h.protocol_version, 1u);
  EXPECT_EQ(h.published, 0u);
  EXPECT_EQ(h.total_bytes, region.geometry().total_bytes);
  EXPECT_EQ(h.channel_mask, kShmAllPixelChannels);

  ShmClient client;
  client.Open(region.params().name.substr(1));  // the leading '/' is optional
  EXPECT_EQ(client.camera(), "uav");
  EXPECT_EQ(client.newest_frame_id(), 0u);
  OwnedFrame frame;
  EXPECT_FALSE(client.ReadNewest(frame));
  EXPECT_TRUE(client.carries(proto::CHANNEL_RGB) && client.carries(proto::CHANNEL_DEPTH) &&
              client.carries(proto::CHANNEL_MASK));
  EXPECT_FALSE(client.carries(proto::CHANNEL_BOXES)) << "boxes are not a pixel channel";
  region.Unlink();
}

TEST(ShmLayout, RgbOnlyRingIsSmallerAndSaysWhatItCarries) {
  auto params = Params(UniqueName("rgb-only"));
  params.channel_mask = ChannelBit(kShmChannelRgb);
  transport::ShmRegion region(params);
  EXPECT_EQ(region.header().channel_mask, 0x02u);
  EXPECT_EQ(region.header().slot_bytes, AlignUp(kShmFrameHeaderBytes + 40 * 30 * 3, 4096));
  ShmClient client;
  client.Open(params.name);
  EXPECT_TRUE(client.carries(proto::CHANNEL_RGB));
  EXPECT_FALSE(client.carries(proto::CHANNEL_DEPTH));
  EXPECT_FALSE(client.carries(proto::CHANNEL_MASK));
  region.Unlink();
}

TEST(ShmLayout, ObjectWithoutAChannelMaskCarriesEveryChannel) {
  // Daemons that predate --shm-channels left the field zero.
  transport::ShmRegion region(Params(UniqueName("no-mask")));
  region.header().channel_mask = 0;
  ShmClient client;
  client.Open(region.params().name);
  EXPECT_TRUE(client.carries(proto::CHANNEL_DEPTH));
  region.Unlink();
}

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

TEST(ShmLayout, WrongLayoutVersionIsAClearError) {
  transport::ShmRegion region(Params(UniqueName("version")));
  region.header().layout_version = 99;
  ExpectOpenFails(region.params().name, {"layout version 99", "layout version 1", region.params().name});
  region.Unlink();
}

TEST(ShmLayout, UnknownChannelBitsAreAClearError) {
  transport::ShmRegion region(Params(UniqueName("bad-mask")));
  region.header().channel_mask = 0x1e;  // BOXES is no pixel channel
  ExpectOpenFails(region.params().name, {"channel mask 30", "RGB, DEPTH and MASK"});
  region.Unlink();
}

TEST(ShmLayout, MissingObjectIsAClearError) {
  ExpectOpenFails(UniqueName("missing"), {"no shared-memory object", "--shm-name"});
}

TEST(ShmLayout, ForeignObjectIsAClearError) {
  const std::string name = UniqueName("foreign");
  const int fd = shm_open(name.c_str(), O_CREAT | O_RDWR | O_TRUNC, 0600);
  ASSERT_GE(fd, 0);
  std::string junk(4096, '\x7f');
  junk.replace(0, 8, "GARBAGE!");
  ASSERT_EQ(write(fd, junk.data(), junk.size()), static_cast<ssize_t>(junk.size()));
  close(fd);
  ExpectOpenFails(name, {"GARBAGE!", "SIM4CVSM", "not a sim4cv ring"});
  shm_unlink(name.c_str());

  const int tiny = shm_open(name.c_str(), O_CREAT | O_RDWR | O_TRUNC, 0600);
  ASSERT_GE(tiny, 0);
  close(tiny);
  ExpectOpenFails(name, {"0 bytes", "smaller than"});
  shm_unlink(name.c_str());
}

TEST(ShmLayout, StaleObjectIsReplaced) {
  const std::string name = UniqueName("stale");
  const int fd = shm_open(name.c_str(), O_CREAT | O_RDWR | O_TRUNC, 0600);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(ftruncate(fd, 100), 0);
  close(fd);
  transport::ShmRegion region(Params(name));
  ShmClient client;
  client.Open(name);
  EXPECT_EQ(client.header().total_bytes, region.geometry().total_bytes);
  region.Unlink();
  ExpectOpenFails(name, {"no shared-memory object"});
}

TEST(ShmLayout, ADaemonNeverRemovesTheObjectThatReplacedItsOwn) {
  const std::string name = UniqueName("twice");
  transport::ShmRegion first(Params(name));
  transport::ShmRegion second(Params(name));  // e.g. a second daemon with the same --shm-name
  first.Unlink();
  ShmClient client;
  client.Open(name);
  EXPECT_EQ(client.header().writer_pid, static_cast<uint32_t>(getpid()));
  second.Unlink();
  ExpectOpenFails(name, {"no shared-memory object"});
}

TEST(ShmLayout, BadParametersAreNamed) {
  auto params = Params("no-slash");
  EXPECT_THROW(transport::ShmRegion{params}, std::invalid_argument);
  params = Params(UniqueName("slots"));
  params.slot_count = 1;
  try {
    transport::ShmRegion region(params);
    ADD_FAILURE() << "one slot accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("--shm-slots 1"), std::string::npos) << error.what();
  }
  for (const uint32_t mask : {0u, 0x10u, 0x0fu}) {
    params = Params(UniqueName("channels"));
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
