// The TCP transport's bounds as units: MessageReader holds only what arrived,
// ConnectionDeadlines says which timeout expired, OfferedReplies stops at its
// byte bound with a fatal Error naming it.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>

#include "protocol/framing.h"
#include "server/common/limits.h"
#include "server/session/offered_replies.h"
#include "server/transport/tcp/connection_deadlines.h"
#include "server/transport/tcp/message_reader.h"

namespace sim4cv::transport {
namespace {

using Status = MessageReader::Status;
using namespace std::chrono_literals;

// Feeds `bytes` to the reader in pieces of at most `piece` bytes.
Status Feed(MessageReader& reader, const std::string& bytes, std::size_t piece) {
  Status status = Status::kNeedMore;
  for (std::size_t done = 0; done < bytes.size();) {
    const std::size_t count = std::min({piece, reader.next_size(), bytes.size() - done});
    std::memcpy(reader.next_data(), bytes.data() + done, count);
    done += count;
    status = reader.Advance(count);
    if (status != Status::kNeedMore) return status;
  }
  return status;
}

std::string Prefix(uint32_t size) {
  std::string prefix(wire::kLengthPrefixBytes, '\0');
  wire::EncodeLengthPrefix(size, reinterpret_cast<uint8_t*>(prefix.data()));
  return prefix;
}

TEST(MessageReaderTest, APrefixAloneAllocatesNothingAndTheBodyGrowsWithWhatArrives) {
  MessageReader reader(64u << 20);
  EXPECT_EQ(Feed(reader, Prefix(64u << 20), 1), Status::kNeedMore);
  EXPECT_TRUE(reader.started());
  EXPECT_LE(reader.held_bytes(), 64u);  // the empty string's own room
  reader.next_data();                   // room for one piece, no more
  EXPECT_LE(reader.held_bytes(), 2 * limits::kReadChunkBytes);
  EXPECT_EQ(Feed(reader, std::string(1u << 20, 'x'), 4096), Status::kNeedMore);
  EXPECT_LE(reader.held_bytes(), 2 * ((1u << 20) + limits::kReadChunkBytes));
}

TEST(MessageReaderTest, WholeMessagesInAnyPiecesAndMemoryGoesBackAfterALargeOne) {
  MessageReader reader(1u << 20);
  const std::string body(300000, 'b');
  for (std::size_t piece : {1u, 7u, 65536u, 1u << 20}) {
    EXPECT_EQ(Feed(reader, Prefix(static_cast<uint32_t>(body.size())) + body, piece), Status::kComplete) << piece;
    EXPECT_EQ(reader.body(), body);
    reader.Next();
    EXPECT_FALSE(reader.started());
    EXPECT_LE(reader.held_bytes(), limits::kKeptBufferBytes);
  }
  EXPECT_EQ(Feed(reader, Prefix(0), 4), Status::kComplete);
  EXPECT_TRUE(reader.body().empty());
}

TEST(MessageReaderTest, APrefixOverTheLimitIsRefusedBeforeAnyBody) {
  MessageReader reader(1000);
  EXPECT_EQ(Feed(reader, Prefix(1000), 4), Status::kNeedMore);
  MessageReader other(1000);
  EXPECT_EQ(Feed(other, Prefix(1001), 4), Status::kTooLarge);
  EXPECT_EQ(other.announced(), 1001u);
  EXPECT_LE(other.held_bytes(), 64u);
}

TEST(ConnectionDeadlinesTest, EachTimeoutInItsState) {
  const auto t0 = ConnectionDeadlines::Clock::now();
  ConnectionDeadlines deadlines({100, 50, 0}, t0);
  EXPECT_EQ(deadlines.next(), t0 + 100ms);
  EXPECT_FALSE(deadlines.Check(t0 + 99ms));
  auto expired = deadlines.Check(t0 + 100ms);
  ASSERT_TRUE(expired);
  EXPECT_EQ(expired->code, proto::ERROR_CODE_NOT_HANDSHAKEN);
  EXPECT_NE(expired->message.find("--handshake-timeout-ms"), std::string::npos);

  deadlines.MessageStarted(t0 + 10ms);  // the Hello starts: the sooner of both
  EXPECT_EQ(deadlines.next(), t0 + 60ms);
  expired = deadlines.Check(t0 + 70ms);
  ASSERT_TRUE(expired);
  EXPECT_NE(expired->message.find("--message-timeout-ms"), std::string::npos);
  deadlines.MessageEnded();
  deadlines.Handshaken();
  EXPECT_EQ(deadlines.next(), ConnectionDeadlines::Clock::time_point::max()) << "idle timeout off by default";
  EXPECT_FALSE(deadlines.Check(t0 + 24h));
}

TEST(ConnectionDeadlinesTest, IdleCountsFromTheLastActivityEitherWay) {
  const auto t0 = ConnectionDeadlines::Clock::now();
  ConnectionDeadlines deadlines({0, 0, 1000}, t0);
  EXPECT_EQ(deadlines.next(), ConnectionDeadlines::Clock::time_point::max()) << "off before the handshake";
  deadlines.Handshaken();
  deadlines.Active(t0 + 500ms);
  EXPECT_EQ(deadlines.next(), t0 + 1500ms);
  EXPECT_FALSE(deadlines.Check(t0 + 1499ms));
  const auto expired = deadlines.Check(t0 + 1500ms);
  ASSERT_TRUE(expired);
  EXPECT_NE(expired->message.find("--idle-timeout-ms"), std::string::npos);
}

proto::Envelope Reply(std::size_t text_bytes) {
  proto::Envelope reply;
  reply.mutable_error()->set_message(std::string(text_bytes, 'e'));
  return reply;
}

TEST(OfferedRepliesTest, OverItsBoundOnlyAFatalErrorNamingTheLimitIsLeft) {
  session::OfferedReplies replies(10000);
  std::vector<proto::Envelope> taken;
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(replies.Offer(Reply(1000)));
  EXPECT_GT(replies.bytes(), 5000u);
  replies.TakeAll(taken);
  EXPECT_EQ(taken.size(), 5u);
  EXPECT_EQ(replies.bytes(), 0u);

  for (int i = 0; i < 9; ++i) EXPECT_TRUE(replies.Offer(Reply(1000)));
  EXPECT_FALSE(replies.Offer(Reply(1000)));
  EXPECT_FALSE(replies.Offer(Reply(1))) << "nothing more once over";
  EXPECT_LT(replies.bytes(), 1000u) << "what waited is dropped";
  replies.TakeAll(taken);
  ASSERT_EQ(taken.size(), 1u);
  EXPECT_TRUE(taken[0].error().fatal());
  EXPECT_EQ(taken[0].error().code(), proto::ERROR_CODE_INVALID_STATE);
  EXPECT_NE(taken[0].error().message().find("kMaxOfferedReplyBytes"), std::string::npos);
  replies.TakeAll(taken);
  EXPECT_TRUE(taken.empty()) << "the Error comes once";
}

}  // namespace
}  // namespace sim4cv::transport
