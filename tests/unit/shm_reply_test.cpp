// Unit tests of the client -> daemon reply ring and the daemon -> client
// response area in one process: the C++ client's producer side
// (clients/cpp/src/shm/shm_requests.cpp) against the daemon's
// ShmReplyReader and ShmResponder (server/transport/shm/).
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "server/transport/shm/shm_reply_reader.h"
#include "server/transport/shm/shm_responder.h"
#include "sim4cv/shm_client.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::transport {
namespace {

using namespace std::chrono_literals;
using Result = ShmReplyReader::Result;

class ShmReplyTest : public ::testing::Test {
 protected:
  void Create(uint32_t capacity, uint32_t entries = 2) {
    ShmRegionParams p;
    p.name = "/sim4cv-unit-reply-" + std::to_string(getpid());
    p.camera_name = "uav";
    p.width = 16;
    p.height = 16;
    p.slot_count = 2;
    p.reply_capacity = capacity;
    p.response_entries = entries;
    region_ = std::make_shared<ShmRegion>(p);
    reader_ = std::make_unique<ShmReplyReader>(region_, counters_, 0ns);
  }
  void TearDown() override {
    if (region_) region_->Unlink();
  }

  // Drains every complete message; returns the TrackerOutput frame ids seen.
  std::vector<uint64_t> Drain(std::set<uint64_t>* tokens = nullptr) {
    std::vector<uint64_t> ids;
    ShmReplyReader::Message message;
    while (reader_->Next(message, std::chrono::steady_clock::now()) == Result::kMessage) {
      proto::Envelope envelope;
      EXPECT_TRUE(envelope.ParseFromArray(message.data, static_cast<int>(message.size)));
      ids.push_back(envelope.tracker_output().frame_id());
      if (tokens) tokens->insert(message.token);
    }
    return ids;
  }

  static void SendId(ShmClient& client, uint64_t id) { client.SendTrackerOutput(id, 1, 2, 3, 4, 0.5f); }

  session::Counters counters_;
  std::shared_ptr<ShmRegion> region_;
  std::unique_ptr<ShmReplyReader> reader_;
};

TEST_F(ShmReplyTest, MessagesArriveInOrderWithTheSendersToken) {
  Create(8);
  ShmClient a, b;
  a.Open(region_->params().name);
  b.Open(region_->params().name);
  EXPECT_NE(a.token(), b.token());
  SendId(a, 1);
  SendId(b, 2);
  SendId(a, 3);
  std::set<uint64_t> tokens;
  EXPECT_EQ(Drain(&tokens), (std::vector<uint64_t>{1, 2, 3}));
  EXPECT_EQ(tokens, (std::set<uint64_t>{a.token(), b.token()}));
  EXPECT_EQ(counters_.Get("shm.replies_dropped"), 0u);
}

TEST_F(ShmReplyTest, FullRingDropsTheOldestAndCountsThem) {
  Create(8);
  ShmClient client;
  client.Open(region_->params().name);
  for (uint64_t id = 0; id < 13; ++id) SendId(client, id);
  EXPECT_EQ(Drain(), (std::vector<uint64_t>{5, 6, 7, 8, 9, 10, 11, 12}));
  EXPECT_EQ(counters_.Get("shm.replies_dropped"), 5u);
  EXPECT_EQ(region_->header().replies_dropped, 5u);
  // The ring keeps working after the overflow.
  SendId(client, 13);
  EXPECT_EQ(Drain(), (std::vector<uint64_t>{13}));
  EXPECT_EQ(counters_.Get("shm.replies_dropped"), 5u);
}

TEST_F(ShmReplyTest, ConcurrentProducersLoseNothingUncounted) {
  Create(64);
  constexpr uint64_t kPerThread = 20000;
  std::atomic<int> finished{0};
  std::vector<std::thread> producers;
  for (uint64_t t = 0; t < 2; ++t) {
    producers.emplace_back([&, t] {
      ShmClient client;
      client.Open(region_->params().name);
      for (uint64_t i = 0; i < kPerThread; ++i) SendId(client, t * kPerThread + i + 1);
      ++finished;
    });
  }
  std::set<uint64_t> seen;
  auto drain_once = [&] {
    for (uint64_t id : Drain()) EXPECT_TRUE(seen.insert(id).second) << "message " << id << " delivered twice";
  };
  while (finished < 2) drain_once();  // the consumer runs while both produce
  for (auto& p : producers) p.join();
  drain_once();
  const uint64_t dropped = counters_.Get("shm.replies_dropped");
  EXPECT_EQ(counters_.Get("shm.replies_corrupt"), 0u);
  EXPECT_EQ(counters_.Get("shm.replies_abandoned"), 0u);
  EXPECT_EQ(seen.size() + dropped, 2 * kPerThread) << "every message is delivered once or counted as dropped";
  EXPECT_GT(seen.size(), 0u);
  std::printf("2 producers x %llu messages into 64 slots: %zu delivered, %llu dropped\n",
              static_cast<unsigned long long>(kPerThread), seen.size(), static_cast<unsigned long long>(dropped));
}

TEST_F(ShmReplyTest, AbandonedReservationIsSkippedAfterATimeout) {
  Create(8);
  ShmClient client;
  client.Open(region_->params().name);
  SendId(client, 1);
  // A client that died right after reserving a ticket.
  shm::Atomic(region_->header().reply_write).fetch_add(1);
  SendId(client, 3);
  const auto start = std::chrono::steady_clock::now();
  ShmReplyReader::Message message;
  ASSERT_EQ(reader_->Next(message, start), Result::kMessage);
  EXPECT_EQ(reader_->Next(message, start), Result::kStalled);
  EXPECT_EQ(reader_->Next(message, start + 100ms), Result::kStalled);
  ASSERT_EQ(reader_->Next(message, start + ShmReplyReader::kAbandonAfter + 1ms), Result::kMessage);
  proto::Envelope envelope;
  ASSERT_TRUE(envelope.ParseFromArray(message.data, static_cast<int>(message.size)));
  EXPECT_EQ(envelope.tracker_output().frame_id(), 3u);
  EXPECT_EQ(counters_.Get("shm.replies_abandoned"), 1u);
}

TEST_F(ShmReplyTest, CorruptMessageIsCountedAndSkipped) {
  Create(8);
  ShmClient client;
  client.Open(region_->params().name);
  SendId(client, 1);
  SendId(client, 2);
  region_->map().reply_slot(0).data[3] ^= 0xff;  // a byte changes behind the checksum
  EXPECT_EQ(Drain(), (std::vector<uint64_t>{2}));
  EXPECT_EQ(counters_.Get("shm.replies_corrupt"), 1u);
}

TEST_F(ShmReplyTest, OversizedEnvelopeIsRefusedByTheClient) {
  Create(8);
  ShmClient client;
  client.Open(region_->params().name);
  proto::Envelope hello;
  hello.mutable_hello()->set_client_name(std::string(300, 'x'));
  try {
    client.SendEnvelope(hello);
    FAIL() << "a 300-byte Hello was sent";
  } catch (const ShmError& error) {
    EXPECT_NE(std::string(error.what()).find("hello is 30"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("at most 232"), std::string::npos) << error.what();
  }
  EXPECT_EQ(region_->header().reply_write, 0u);
}

TEST_F(ShmReplyTest, ResponsesReachOnlyTheirClient) {
  Create(8, 2);
  ShmResponder responder(region_);
  ShmClient a, b;
  a.Open(region_->params().name);
  b.Open(region_->params().name);
  const int entry_a = responder.Assign(a.token());
  const int entry_b = responder.Assign(b.token());
  ASSERT_GE(entry_a, 0);
  ASSERT_GE(entry_b, 0);
  EXPECT_EQ(responder.Assign(12345), -1) << "only two entries";
  proto::Envelope reply;
  reply.mutable_state()->set_frame_id(7);
  ASSERT_TRUE(responder.Write(entry_a, reply));
  proto::Envelope got;
  ASSERT_TRUE(a.ReceiveReply(got, 1000ms));
  EXPECT_EQ(got.state().frame_id(), 7u);
  EXPECT_FALSE(b.ReceiveReply(got, 20ms));
  EXPECT_FALSE(a.ReceiveReply(got, 20ms));

  // A waiting client wakes when its response is written.
  std::thread writer([&] {
    std::this_thread::sleep_for(50ms);
    proto::Envelope later;
    later.mutable_subscribed()->set_camera("uav");
    responder.Write(entry_b, later);
  });
  ASSERT_TRUE(b.ReceiveReply(got, 5000ms));
  EXPECT_EQ(got.subscribed().camera(), "uav");
  writer.join();

  // More responses than the entry holds: the oldest are lost, and counted.
  for (uint64_t i = 0; i < shm::kShmResponseDepth + 3; ++i) {
    reply.mutable_state()->set_frame_id(100 + i);
    ASSERT_TRUE(responder.Write(entry_a, reply));
  }
  ASSERT_TRUE(a.ReceiveReply(got, 1000ms));
  EXPECT_EQ(got.state().frame_id(), 103u);
  EXPECT_EQ(a.responses_lost(), 3u);

  // Too large for a response message: refused, nothing written.
  proto::Envelope huge;
  huge.mutable_error()->set_message(std::string(shm::kShmResponseDataBytes, 'x'));
  EXPECT_FALSE(responder.Write(entry_a, huge));

  // A freed entry: the client learns the daemon forgot it.
  responder.Free(entry_b);
  EXPECT_THROW(b.ReceiveReply(got, 1000ms), ConnectionError);
}

}  // namespace
}  // namespace sim4cv::transport
