// Unit tests of UDP frame delivery's pure logic: the daemon's FrameChunker
// (server/transport/udp/frame_chunker.*) cutting an encoded frame into
// datagrams, the client's reassembly (clients/cpp/src/udp/frame_reassembler.*)
// putting it back, and the daemon's sequence filter and reply rate limit.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "clients/cpp/src/udp/frame_reassembler.h"
#include "server/transport/frame_encoding.h"
#include "server/transport/udp/frame_chunker.h"
#include "server/transport/udp/rate_limiter.h"
#include "server/transport/udp/sequence_filter.h"
#include "tests/support/no_warnings.h"

// Chunking and reassembly must allocate nothing once warm.
#include "tests/support/allocation_counter.h"

namespace sim4cv::transport {
namespace {

using detail::ChunkView;
using detail::ClassifyDatagram;
using detail::DatagramKind;
using detail::FrameReassembler;
using Result = FrameReassembler::Result;

constexpr uint32_t kMaxFrame = 64u << 20;

// A frame whose pixels are all different, so a misplaced byte shows.
void FillFrame(session::Frame& f, uint64_t frame_id, uint32_t width, uint32_t height) {
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  f.frame_id = frame_id;
  f.sim_time = static_cast<double>(frame_id) / 30;
  f.width = width;
  f.height = height;
  f.render_end_mono_ns = 123456789;
  const auto rgb = f.Hold(proto::CHANNEL_RGB);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<uint8_t>(i * 7 + frame_id);
  const auto depth = f.Hold<float>(proto::CHANNEL_DEPTH);
  for (std::size_t i = 0; i < pixels; ++i) depth[i] = 0.25f * static_cast<float>(i);
  const auto mask = f.Hold<uint16_t>(proto::CHANNEL_MASK);
  for (std::size_t i = 0; i < pixels; ++i) mask[i] = static_cast<uint16_t>(i * 31);
  render::GroundTruthBox car;
  car.instance = 1;
  car.object_class = proto::OBJECT_CLASS_CAR;
  car.x = 3;
  car.y = 4;
  car.width = 5;
  car.height = 6;
  car.visible_pixels = 30;
  car.visibility = 1.0f;
  f.boxes = {car};
}

class UdpChunkingTest : public ::testing::Test {
 protected:
  // Encodes frame `frame_id` (all channels) and cuts it for `datagram_bytes`;
  // returns the datagrams and leaves the encoded envelope in `encoded_`.
  std::vector<std::string> Chunk(uint64_t frame_id, std::size_t datagram_bytes, uint32_t width = 64,
                                 uint32_t height = 48) {
    session::Frame* writable = nullptr;
    frames_.push_back(pool_.Acquire(&writable));
    FillFrame(*writable, frame_id, width, height);
    proto::Subscribed subscription;
    subscription.set_camera("uav");
    for (auto c : {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_MASK, proto::CHANNEL_BOXES}) {
      subscription.add_channels(c);
    }
    encoder_.Encode(*writable, "uav", subscription, false, 0, false);
    encoded_.clear();
    for (const Segment& s : encoder_.segments()) encoded_.append(reinterpret_cast<const char*>(s.data), s.size);

    FrameChunker chunker(datagram_bytes);
    chunker.Start(frame_id, encoder_.segments(), encoder_.total_size());
    std::vector<std::string> datagrams;
    for (uint32_t i = 0; i < chunker.chunk_count(); ++i) {
      FrameChunker::Header header;
      iovec iov[FrameChunker::kMaxIovecs];
      const std::size_t used = chunker.Build(i, header, iov);
      EXPECT_LE(used, FrameChunker::kMaxIovecs);
      std::string datagram;
      for (std::size_t k = 0; k < used; ++k) datagram.append(static_cast<const char*>(iov[k].iov_base), iov[k].iov_len);
      EXPECT_LE(datagram.size(), datagram_bytes) << "chunk " << i;
      datagrams.push_back(std::move(datagram));
    }
    return datagrams;
  }

  static Result Feed(FrameReassembler& reassembler, const std::string& datagram) {
    ChunkView chunk;
    EXPECT_EQ(ClassifyDatagram(reinterpret_cast<const uint8_t*>(datagram.data()), datagram.size(), chunk),
              DatagramKind::kChunk);
    return reassembler.Add(chunk);
  }

  // A hand-made chunk datagram, encoded by protobuf itself.
  static std::string MakeChunk(uint64_t frame_id, uint32_t index, uint32_t count, uint32_t frame_bytes,
                               uint32_t offset, const std::string& data) {
    proto::Envelope envelope;
    proto::FrameChunk& chunk = *envelope.mutable_frame_chunk();
    chunk.set_frame_id(frame_id);
    chunk.set_chunk_index(index);
    chunk.set_chunk_count(count);
    chunk.set_frame_bytes(frame_bytes);
    chunk.set_offset(offset);
    chunk.set_data(data);
    return envelope.SerializeAsString();
  }

  session::FramePool pool_;
  std::vector<session::FrameRef> frames_;
  FrameEncoder encoder_;
  std::string encoded_;
};

TEST_F(UdpChunkingTest, DatagramsParseAsFrameChunksAndTileTheFrame) {
  for (const std::size_t size : {std::size_t{44}, std::size_t{100}, std::size_t{576}, std::size_t{1472},
                                 std::size_t{9000}, std::size_t{65000}, FrameChunker::kMaxDatagramBytes}) {
    SCOPED_TRACE("datagram bytes " + std::to_string(size));
    const auto datagrams = Chunk(77, size);
    const std::size_t payload = size - FrameChunker::kMaxHeaderBytes;
    ASSERT_EQ(datagrams.size(), (encoded_.size() + payload - 1) / payload);
    std::string joined;
    for (std::size_t i = 0; i < datagrams.size(); ++i) {
      proto::Envelope envelope;
      ASSERT_TRUE(envelope.ParseFromString(datagrams[i]));  // protobuf reads the hand-made header
      ASSERT_TRUE(envelope.has_frame_chunk());
      const proto::FrameChunk& chunk = envelope.frame_chunk();
      EXPECT_EQ(chunk.frame_id(), 77u);
      EXPECT_EQ(chunk.chunk_index(), i);
      EXPECT_EQ(chunk.chunk_count(), datagrams.size());
      EXPECT_EQ(chunk.frame_bytes(), encoded_.size());
      EXPECT_EQ(chunk.offset(), joined.size());
      joined += chunk.data();
    }
    EXPECT_EQ(joined, encoded_);
  }
  EXPECT_THROW(FrameChunker(FrameChunker::kMaxHeaderBytes), std::invalid_argument);
  EXPECT_THROW(FrameChunker(FrameChunker::kMaxDatagramBytes + 1), std::invalid_argument);
}

TEST_F(UdpChunkingTest, ReassemblesInOrderAndShuffled) {
  std::mt19937 random(42);
  uint64_t frame_id = 1;
  for (const std::size_t size : {std::size_t{100}, std::size_t{1472}, std::size_t{65000}}) {
    for (const bool shuffle : {false, true}) {
      SCOPED_TRACE("datagram bytes " + std::to_string(size) + (shuffle ? ", shuffled" : ""));
      auto datagrams = Chunk(frame_id, size);
      if (shuffle) std::shuffle(datagrams.begin(), datagrams.end(), random);
      FrameReassembler reassembler(kMaxFrame);
      for (std::size_t i = 0; i + 1 < datagrams.size(); ++i) EXPECT_EQ(Feed(reassembler, datagrams[i]), Result::kPending);
      ASSERT_EQ(Feed(reassembler, datagrams.back()), Result::kComplete);
      EXPECT_EQ(reassembler.frame(), encoded_);
      proto::Envelope envelope;
      ASSERT_TRUE(envelope.ParseFromArray(reassembler.frame().data(), static_cast<int>(reassembler.frame().size())));
      EXPECT_EQ(envelope.frame().frame_id(), frame_id);
      EXPECT_EQ(envelope.frame().images_size(), 3);
      EXPECT_EQ(envelope.frame().boxes_size(), 1);
      EXPECT_EQ(reassembler.frames_completed(), 1u);
      EXPECT_EQ(reassembler.chunks_ignored(), 0u);
      // A repeat of a finished frame's chunk is ignored, not a new frame.
      EXPECT_EQ(Feed(reassembler, datagrams.front()), Result::kIgnored);
      EXPECT_EQ(reassembler.chunks_ignored(), 1u);
      ++frame_id;
    }
  }
}

TEST_F(UdpChunkingTest, MissingChunkDropsTheFrameWhenANewerOneOvertakes) {
  FrameReassembler reassembler(kMaxFrame);
  auto first = Chunk(10, 1472);
  ASSERT_GT(first.size(), 3u);
  first.erase(first.begin() + 2);  // lost on the way
  for (const auto& d : first) EXPECT_EQ(Feed(reassembler, d), Result::kPending);
  const auto second = Chunk(11, 1472);
  for (std::size_t i = 0; i + 1 < second.size(); ++i) EXPECT_EQ(Feed(reassembler, second[i]), Result::kPending);
  EXPECT_EQ(reassembler.frames_dropped_incomplete(), 1u);  // frame 10, never delivered
  ASSERT_EQ(Feed(reassembler, second.back()), Result::kComplete);
  EXPECT_EQ(reassembler.frame(), encoded_);
  EXPECT_EQ(reassembler.frames_completed(), 1u);
  // The lost chunk arriving late cannot revive frame 10.
  const auto late = Chunk(10, 1472);
  EXPECT_EQ(Feed(reassembler, late[2]), Result::kIgnored);
  EXPECT_EQ(reassembler.chunks_ignored(), 1u);
}

// LoadMap and Reset start frame ids from 0 again: the next frame (id 1 or
// 2, lower than the last one finished) is reassembled, not ignored as old.
TEST_F(UdpChunkingTest, FrameIdsThatStartAgainAreReassembled) {
  FrameReassembler reassembler(kMaxFrame);
  const auto before = Chunk(42, 1472);
  for (const auto& d : before) Feed(reassembler, d);
  ASSERT_EQ(reassembler.frames_completed(), 1u);
  const auto late = Chunk(41, 1472);
  EXPECT_EQ(Feed(reassembler, late[1]), Result::kIgnored);  // a late chunk of an old frame: still ignored
  const auto restarted = Chunk(1, 1472);
  for (std::size_t i = 0; i + 1 < restarted.size(); ++i) EXPECT_EQ(Feed(reassembler, restarted[i]), Result::kPending);
  ASSERT_EQ(Feed(reassembler, restarted.back()), Result::kComplete);
  EXPECT_EQ(reassembler.frame(), encoded_);
  EXPECT_EQ(reassembler.frames_completed(), 2u);
  EXPECT_EQ(Feed(reassembler, restarted[0]), Result::kIgnored);  // a duplicate of the frame just finished
}

TEST_F(UdpChunkingTest, OlderFrameChunksAreIgnoredWhileANewerOneIsInProgress) {
  FrameReassembler reassembler(kMaxFrame);
  const auto newer = Chunk(21, 1472);
  const auto older = Chunk(20, 1472);
  EXPECT_EQ(Feed(reassembler, newer[0]), Result::kPending);
  EXPECT_EQ(Feed(reassembler, older[0]), Result::kIgnored);
  EXPECT_EQ(Feed(reassembler, newer[0]), Result::kIgnored);  // duplicate
  EXPECT_EQ(reassembler.chunks_ignored(), 2u);
  EXPECT_EQ(reassembler.frames_dropped_incomplete(), 0u);
}

TEST_F(UdpChunkingTest, InconsistentChunksAreIgnoredAndCounted) {
  FrameReassembler reassembler(1000);
  const std::string data(10, 'x');
  const std::vector<std::string> bad = {
      MakeChunk(5, 3, 3, 30, 0, data),    // index == count
      MakeChunk(5, 7, 3, 30, 0, data),    // index beyond count
      MakeChunk(5, 0, 0, 30, 0, data),    // no chunks
      MakeChunk(5, 0, 3, 0, 0, data),     // empty frame
      MakeChunk(5, 0, 3, 5000, 0, data),  // larger than the limit
      MakeChunk(5, 0, 3, 30, 25, data),   // runs past the frame's end
      MakeChunk(5, 0, 3, 30, 0, ""),      // no data
  };
  for (const auto& d : bad) EXPECT_EQ(Feed(reassembler, d), Result::kIgnored);
  EXPECT_EQ(reassembler.chunks_ignored(), bad.size());
  // A good chunk starts frame 5; chunks disagreeing with it are ignored.
  EXPECT_EQ(Feed(reassembler, MakeChunk(5, 0, 3, 30, 0, data)), Result::kPending);
  EXPECT_EQ(Feed(reassembler, MakeChunk(5, 1, 4, 30, 10, data)), Result::kIgnored);
  EXPECT_EQ(Feed(reassembler, MakeChunk(5, 1, 3, 40, 10, data)), Result::kIgnored);
  EXPECT_EQ(Feed(reassembler, MakeChunk(5, 1, 3, 30, 10, data)), Result::kPending);
  EXPECT_EQ(Feed(reassembler, MakeChunk(5, 2, 3, 30, 20, data)), Result::kComplete);
  EXPECT_EQ(reassembler.frame(), std::string(30, 'x'));
  EXPECT_EQ(reassembler.chunks_ignored(), bad.size() + 2);
}

TEST_F(UdpChunkingTest, ClassifiesDatagrams) {
  ChunkView chunk;
  auto classify = [&](const std::string& d) {
    return ClassifyDatagram(reinterpret_cast<const uint8_t*>(d.data()), d.size(), chunk);
  };
  proto::Envelope state;
  state.mutable_state()->set_frame_id(3);
  state.set_sequence(9);
  EXPECT_EQ(classify(state.SerializeAsString()), DatagramKind::kOther);
  EXPECT_EQ(classify(""), DatagramKind::kOther);  // an empty Envelope
  EXPECT_EQ(classify(std::string("\xff\xff\xff\xff", 4)), DatagramKind::kMalformed);
  const std::string good = MakeChunk(8, 1, 2, 20, 10, std::string(10, 'y'));
  const std::string sequenced = good + std::string("\xa0\x06\x05", 3);  // plus Envelope.sequence 5
  EXPECT_EQ(classify(sequenced), DatagramKind::kChunk);  // chunk.data points into `sequenced`
  EXPECT_EQ(chunk.frame_id, 8u);
  EXPECT_EQ(chunk.chunk_index, 1u);
  EXPECT_EQ(chunk.offset, 10u);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(chunk.data), chunk.size), std::string(10, 'y'));
  // Cut short: the datagram ends before the length its protobuf announces.
  EXPECT_EQ(classify(good.substr(0, good.size() - 3)), DatagramKind::kMalformed);
}

TEST_F(UdpChunkingTest, ChunkingAndReassemblyAllocateNothingOnceWarm) {
  session::Frame* writable = nullptr;
  const session::FrameRef frame = pool_.Acquire(&writable);
  FillFrame(*writable, 1, 320, 180);
  proto::Subscribed subscription;
  subscription.set_camera("uav");
  subscription.add_channels(proto::CHANNEL_RGB);
  subscription.add_channels(proto::CHANNEL_BOXES);
  FrameChunker chunker(1472);
  FrameReassembler reassembler(kMaxFrame);
  std::vector<std::string> datagrams(1000, std::string(1472, '\0'));  // the "network"
  auto round = [&](uint64_t frame_id) {
    writable->frame_id = frame_id;
    encoder_.Encode(*frame, "uav", subscription, false, 0, false);
    chunker.Start(frame_id, encoder_.segments(), encoder_.total_size());
    Result last = Result::kIgnored;
    for (uint32_t i = 0; i < chunker.chunk_count(); ++i) {
      FrameChunker::Header header;
      iovec iov[FrameChunker::kMaxIovecs];
      const std::size_t used = chunker.Build(i, header, iov);
      std::string& datagram = datagrams[i];
      datagram.clear();  // keeps its capacity
      for (std::size_t k = 0; k < used; ++k) datagram.append(static_cast<const char*>(iov[k].iov_base), iov[k].iov_len);
      ChunkView chunk;
      ClassifyDatagram(reinterpret_cast<const uint8_t*>(datagram.data()), datagram.size(), chunk);
      last = reassembler.Add(chunk);
    }
    return last;
  };
  ASSERT_EQ(round(1), Result::kComplete);  // warm-up: buffers reach their size
  ASSERT_EQ(testing::AllocationsIn([] { ::operator delete(::operator new(16)); }), 1u);  // the counter works
  Result second = Result::kComplete;
  EXPECT_EQ(testing::AllocationsIn([&] { second = round(2); }), 0u);
  EXPECT_EQ(second, Result::kComplete);
}

TEST(SequenceFilterTest, AppliesOnlyIncreasingSequences) {
  SequenceFilter filter;
  EXPECT_TRUE(filter.Accept(1));
  EXPECT_TRUE(filter.Accept(5));
  EXPECT_FALSE(filter.Accept(5));  // duplicate
  EXPECT_FALSE(filter.Accept(3));  // late
  EXPECT_TRUE(filter.Accept(0));   // unsequenced: always
  EXPECT_TRUE(filter.Accept(0));
  EXPECT_TRUE(filter.Accept(6));
  EXPECT_EQ(filter.last_applied(), 6u);
}

TEST(RateLimiterTest, AllowsABurstThenTheRate) {
  RateLimiter limiter(10, 3);
  const auto start = RateLimiter::Clock::now();
  int allowed = 0;
  for (int i = 0; i < 100; ++i) allowed += limiter.Allow(start) ? 1 : 0;
  EXPECT_EQ(allowed, 3);
  EXPECT_FALSE(limiter.Allow(start + std::chrono::milliseconds(50)));
  EXPECT_TRUE(limiter.Allow(start + std::chrono::milliseconds(150)));
}

}  // namespace
}  // namespace sim4cv::transport
