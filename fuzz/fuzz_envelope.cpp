// Fuzz target: the TCP session's read path (server/transport/tcp/tcp_session.cpp,
// OnRead and HandleRequest) without the socket. The input is the byte stream a
// client sends: MessageReader cuts it into length-prefixed messages in the
// pieces it asks for, each body is parsed as an Envelope and handed to a fresh
// ClientProtocol, until the reader or the protocol ends the connection (a
// message over --max-message-bytes, a malformed body, a fatal Error).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "fuzz/protocol_harness.h"
#include "server/transport/tcp/message_reader.h"

namespace {

using sim4cv::session::ClientProtocol;
using sim4cv::transport::MessageReader;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  sim4cv::fuzz::ProtocolHarness& harness = sim4cv::fuzz::SharedHarness();
  sim4cv::fuzz::FuzzSession session(harness.context());
  MessageReader reader(harness.context().max_message_bytes);
  sim4cv::proto::Envelope request, reply;
  std::size_t at = 0;
  while (at < size) {
    const std::size_t piece = std::min(reader.next_size(), size - at);
    std::memcpy(reader.next_data(), data + at, piece);
    at += piece;
    const MessageReader::Status status = reader.Advance(piece);
    if (status == MessageReader::Status::kNeedMore) continue;
    if (status == MessageReader::Status::kTooLarge) break;                      // refused: the session closes
    ClientProtocol::Outcome outcome = ClientProtocol::Outcome::kReplyAndClose;  // a malformed body
    if (request.ParseFromString(reader.body())) outcome = session.protocol.Handle(request, reply);
    reader.Next();
    if (outcome != ClientProtocol::Outcome::kNoReply) (void)reply.ByteSizeLong();  // what QueueEnvelope encodes
    harness.DrainCommands();
    if (outcome == ClientProtocol::Outcome::kReplyAndClose) break;
  }
  harness.DrainCommands();
  return 0;
}
