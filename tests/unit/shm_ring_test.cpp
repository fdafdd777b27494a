// Unit tests of the frame ring in one process: the daemon's writer
// (server/transport/shm/shm_ring_writer.*) against the C++ client's readers
// (clients/cpp/src/shm/). A writer thread hammers a small ring while readers
// check that no torn frame is ever accepted; views of overwritten slots
// report stale without holding the writer back; WaitForFrame wakes.
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <memory>
#include <string>
#include <thread>

#include "server/transport/shm/shm_ring_writer.h"
#include "sim4cv/shm_client.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::transport {
namespace {

using namespace std::chrono_literals;
constexpr uint32_t kWidth = 48, kHeight = 32;

ShmRegionParams Params(const std::string& /*what*/, uint32_t slots) {
  ShmRegionParams p;
  p.camera_name = "uav";
  p.width = kWidth;
  p.height = kHeight;
  p.slot_count = slots;  // the default channels: the planes FillFrame holds
  return p;
}

// Every value of frame `id` derives from id, so a mix of two frames shows.
void FillFrame(session::Frame& f, uint64_t id) {
  f.frame_id = id;
  f.sim_time = static_cast<double>(id) * 0.5;
  f.camera_index = 0;
  f.width = kWidth;
  f.height = kHeight;
  f.render_end_mono_ns = static_cast<int64_t>(id) * 7;
  const auto rgb = f.Hold(proto::CHANNEL_RGB);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<uint8_t>(id + i);
  std::ranges::fill(f.Hold<float>(proto::CHANNEL_DEPTH), static_cast<float>(id % 1000000));
  std::ranges::fill(f.Hold<uint16_t>(proto::CHANNEL_MASK), static_cast<uint16_t>(id));
  f.boxes.resize(id % 4);
  for (std::size_t b = 0; b < f.boxes.size(); ++b) {
    f.boxes[b] = {static_cast<uint16_t>(b + 1), 1, static_cast<uint32_t>(id), 2, 3, 4, 99, 0.5f};
  }
  f.state.Clear();
  proto::EntityState* car = f.state.add_entities();
  car->set_id(1);
  car->mutable_position()->set_x(static_cast<double>(id));
}

// Returns an empty string if `frame` is frame `id` throughout.
std::string Inconsistency(const OwnedFrame& f) {
  const uint64_t id = f.frame_id;
  if (f.sim_time != static_cast<double>(id) * 0.5) return "sim_time";
  if (f.render_end_mono_ns != static_cast<int64_t>(id) * 7) return "render_end_mono_ns";
  const auto& rgb = f.planes[*channels::IndexOf(proto::CHANNEL_RGB)];
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    if (rgb[i] != static_cast<uint8_t>(id + i)) return "rgb byte " + std::to_string(i);
  }
  const auto depth = f.image(proto::CHANNEL_DEPTH);
  const auto mask = f.image(proto::CHANNEL_MASK);
  if (!depth || !mask) return "depth or mask missing";
  for (uint32_t i = 0; i < f.width * f.height; ++i) {
    if (*depth->at<float>(i, 0) != static_cast<float>(id % 1000000)) return "depth";
    if (*mask->at<uint16_t>(i, 0) != static_cast<uint16_t>(id)) return "mask";
  }
  if (f.boxes.size() != id % 4) return "box count";
  for (const auto& box : f.boxes) {
    if (box.x != static_cast<uint32_t>(id)) return "box x";
  }
  if (f.entities.size() != 1 || f.entities[0].position[0] != static_cast<double>(id)) return "entity pose";
  return "";
}

TEST(ShmRing, HammeredRingNeverYieldsATornFrame) {
  auto region = std::make_shared<ShmRegion>(Params("hammer", 2));  // 2 slots: maximal reuse
  ShmRingWriter writer(region, 0);
  std::atomic<bool> done{false};
  std::atomic<uint64_t> written{0};
  std::thread writer_thread([&] {
    session::Frame frame;
    for (uint64_t id = 1; !done; ++id) {
      FillFrame(frame, id);
      writer.Write(frame);
      written = id;
    }
  });

  ShmClient client;
  client.OpenFrames(region->fd());
  OwnedFrame frame;
  uint64_t copies = 0, views_accepted = 0, views_stale = 0, last_id = 0;
  const auto end = std::chrono::steady_clock::now() + 1500ms;
  while (std::chrono::steady_clock::now() < end) {
    if (!client.ReadNewest(frame)) continue;
    ++copies;
    const std::string problem = Inconsistency(frame);
    ASSERT_EQ(problem, "") << "torn copy of frame " << frame.frame_id;
    ASSERT_GE(frame.frame_id, last_id) << "the newest frame went backwards";
    last_id = frame.frame_id;

    FrameView view;
    ASSERT_TRUE(client.AcquireNewest(view));
    const uint64_t id = view.frame_id();
    const auto rgb = view.image(proto::CHANNEL_RGB);
    const auto mask = view.image(proto::CHANNEL_MASK);
    ASSERT_TRUE(rgb && mask);
    bool consistent = rgb->stride == kWidth * 3 && view.boxes().size() == id % 4;
    for (uint32_t i = 0; i < kWidth * kHeight * 3; ++i)
      consistent = consistent && rgb->data[i] == static_cast<uint8_t>(id + i);
    const auto* mask_pixels = reinterpret_cast<const uint16_t*>(mask->data);
    for (uint32_t i = 0; i < kWidth * kHeight; ++i)
      consistent = consistent && mask_pixels[i] == static_cast<uint16_t>(id);
    if (view.stale()) {
      ++views_stale;  // the writer got there first: a reader must discard it
      EXPECT_THROW(view.Validate(), ShmError);
    } else {
      ++views_accepted;
      ASSERT_TRUE(consistent) << "a view that is not stale had torn pixels (frame " << id << ")";
    }
  }
  done = true;
  writer_thread.join();
  EXPECT_GT(written.load(), 1000u);
  EXPECT_GT(copies, 100u);
  EXPECT_GT(views_accepted, 0u);
  std::printf("writer published %llu frames; reader copied %llu consistent frames; views: %llu accepted, %llu stale\n",
              static_cast<unsigned long long>(written.load()), static_cast<unsigned long long>(copies),
              static_cast<unsigned long long>(views_accepted), static_cast<unsigned long long>(views_stale));
}

TEST(ShmRing, UnreleasedViewGoesStaleWithoutBlockingTheWriter) {
  auto region = std::make_shared<ShmRegion>(Params("stale-view", 3));
  ShmRingWriter writer(region, 0);
  session::Frame frame;
  FillFrame(frame, 1);
  writer.Write(frame);
  ShmClient client;
  client.OpenFrames(region->fd());
  FrameView view;
  ASSERT_TRUE(client.AcquireNewest(view));
  EXPECT_EQ(view.frame_id(), 1u);
  EXPECT_EQ(view.publication(), 1u);
  EXPECT_EQ(view.width(), kWidth);
  ASSERT_EQ(view.entities().size(), 1u);
  EXPECT_FALSE(view.stale());
  // Two more frames fill the other slots; the view's slot is untouched.
  for (uint64_t id = 2; id <= 3; ++id) {
    FillFrame(frame, id);
    writer.Write(frame);
  }
  EXPECT_FALSE(view.stale());
  view.Validate();
  // The fourth frame reuses slot 0 at once: the writer never waits for the view.
  FillFrame(frame, 4);
  writer.Write(frame);
  EXPECT_TRUE(view.stale());
  EXPECT_EQ(client.newest_frame_id(), 4u);
  EXPECT_EQ(view.frame_id(), 1u) << "the view's metadata is a copy and stays as acquired";
  view.Release();
  EXPECT_FALSE(view.valid());
  EXPECT_TRUE(view.stale());
}

// A ring carrying some channels: those come through intact, the others are
// reported absent by every accessor and their records hold zeros, not garbage.
TEST(ShmRing, RingWithoutSomeChannelsReportsThemAbsent) {
  auto params = Params("channels", 2);
  params.channel_mask = channels::Bit(proto::CHANNEL_RGB);
  auto region = std::make_shared<ShmRegion>(params);
  ShmRingWriter writer(region, 0);
  ShmClient client;
  client.OpenFrames(region->fd());
  OwnedFrame owned;
  session::Frame frame;
  // A reused OwnedFrame: its depth and mask must not keep an earlier frame's pixels.
  owned.planes[*channels::IndexOf(proto::CHANNEL_DEPTH)].assign(16, 1);
  owned.planes[*channels::IndexOf(proto::CHANNEL_MASK)].assign(8, 1);
  FillFrame(frame, 3);
  writer.Write(frame);
  ASSERT_TRUE(client.ReadNewest(owned));
  EXPECT_TRUE(std::ranges::equal(owned.planes[*channels::IndexOf(proto::CHANNEL_RGB)], frame.Plane(proto::CHANNEL_RGB)));
  EXPECT_TRUE(owned.has(proto::CHANNEL_RGB));
  EXPECT_FALSE(owned.has(proto::CHANNEL_DEPTH));
  EXPECT_FALSE(owned.has(proto::CHANNEL_MASK));
  EXPECT_TRUE(owned.planes[*channels::IndexOf(proto::CHANNEL_DEPTH)].empty() &&
              owned.planes[*channels::IndexOf(proto::CHANNEL_MASK)].empty());
  EXPECT_EQ(owned.boxes.size(), 3u) << "boxes and poses come with any channel set";
  EXPECT_EQ(owned.entities.size(), 1u);

  FrameView view;
  ASSERT_TRUE(client.AcquireNewest(view));
  EXPECT_TRUE(view.has(proto::CHANNEL_RGB));
  EXPECT_FALSE(view.has(proto::CHANNEL_DEPTH));
  EXPECT_FALSE(view.has(proto::CHANNEL_MASK));
  EXPECT_FALSE(view.has(proto::CHANNEL_UNSPECIFIED));
  EXPECT_FALSE(view.image(proto::CHANNEL_DEPTH).has_value());
  EXPECT_FALSE(view.image(proto::CHANNEL_MASK).has_value());
  EXPECT_FALSE(view.image(proto::CHANNEL_UNSPECIFIED).has_value())
      << "channel 0 must not match an absent channel's all-zero record";
  const auto rgb = view.image(proto::CHANNEL_RGB);
  ASSERT_TRUE(rgb.has_value());
  EXPECT_EQ(std::memcmp(rgb->data, frame.Pixels(proto::CHANNEL_RGB), frame.Plane(proto::CHANNEL_RGB).size()), 0);
  const shm::ShmFrameHeader& slot = region->map().slot(0);
  EXPECT_EQ(slot.channel_mask, 0x02u);
  EXPECT_EQ(slot.channel_count, channels::kPixelChannelCount);
  for (std::size_t absent = 1; absent < channels::kPixelChannelCount; ++absent) {
    const shm::ShmChannel& record = slot.channels[absent];
    EXPECT_TRUE(record.channel == 0 && record.format == 0 && record.stride == 0 && record.offset == 0 &&
                record.bytes == 0)
        << "record " << absent;
  }
  EXPECT_FALSE(view.stale());
}

TEST(ShmRing, RingWithoutRgbPacksTheOtherPlanes) {
  auto params = Params("no-rgb", 2);
  params.channel_mask = channels::Bit(proto::CHANNEL_DEPTH) | channels::Bit(proto::CHANNEL_MASK);
  auto region = std::make_shared<ShmRegion>(params);
  ShmRingWriter writer(region, 0);
  ShmClient client;
  client.OpenFrames(region->fd());
  session::Frame frame;
  FillFrame(frame, 8);
  writer.Write(frame);
  OwnedFrame owned;
  ASSERT_TRUE(client.ReadNewest(owned));
  EXPECT_TRUE(owned.planes[*channels::IndexOf(proto::CHANNEL_RGB)].empty());
  EXPECT_TRUE(std::ranges::equal(owned.planes[*channels::IndexOf(proto::CHANNEL_DEPTH)], frame.Plane(proto::CHANNEL_DEPTH)));
  EXPECT_TRUE(std::ranges::equal(owned.planes[*channels::IndexOf(proto::CHANNEL_MASK)], frame.Plane(proto::CHANNEL_MASK)));
  FrameView view;
  ASSERT_TRUE(client.AcquireNewest(view));
  EXPECT_FALSE(view.image(proto::CHANNEL_RGB).has_value());
  const auto depth = view.image(proto::CHANNEL_DEPTH);
  ASSERT_TRUE(depth.has_value());
  // Slot 0, right after its header: where RGB would have been.
  const auto* client_base = reinterpret_cast<const uint8_t*>(&client.header());
  EXPECT_EQ(depth->data, client_base + client.header().slots_offset + shm::kShmFrameHeaderBytes);
  EXPECT_EQ(depth->stride, kWidth * 4);
}

TEST(ShmRing, IgnoresFramesOfOtherCameras) {
  auto region = std::make_shared<ShmRegion>(Params("camera", 2));
  ShmRingWriter writer(region, 1);
  session::Frame frame;
  FillFrame(frame, 5);  // camera 0
  writer.Write(frame);
  EXPECT_EQ(region->header().published, 0u);
  frame.camera_index = 1;
  writer.Write(frame);
  EXPECT_EQ(region->header().published, 1u);
}

TEST(ShmRing, WaitForFrameWakesOnPublishAndOnClose) {
  auto region = std::make_shared<ShmRegion>(Params("wait", 2));
  ShmRingWriter writer(region, 0);
  ShmClient client;
  client.OpenFrames(region->fd());
  EXPECT_FALSE(client.WaitForFrame(0, 20ms));
  std::thread publisher([&] {
    std::this_thread::sleep_for(50ms);
    session::Frame frame;
    FillFrame(frame, 9);
    writer.Write(frame);
  });
  const auto start = std::chrono::steady_clock::now();
  EXPECT_TRUE(client.WaitForFrame(0, 60000ms));
  EXPECT_LT(std::chrono::steady_clock::now() - start, 30000ms);  // woken by the write, not the 60 s timeout
  publisher.join();
  EXPECT_EQ(client.newest_frame_id(), 9u);
  EXPECT_TRUE(client.WaitForFrame(8, 0ms));
  EXPECT_FALSE(client.WaitForFrame(9, 10ms));
  std::thread closer([&] {
    std::this_thread::sleep_for(50ms);
    writer.Close();
  });
  EXPECT_THROW(client.WaitForFrame(9, 5000ms), ConnectionError);
  closer.join();
  EXPECT_TRUE(client.closed());
}

}  // namespace
}  // namespace sim4cv::transport
