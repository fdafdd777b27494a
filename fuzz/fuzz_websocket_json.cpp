// Fuzz target: the WebSocket session's read path (server/transport/http/
// ws_session.cpp, HandleMessage) without the socket. The input is the text
// messages a page sends, one per line: each is parsed by EnvelopeFromJson
// (protobuf's JSON mapping; a failure is a non-fatal Error there) and handed
// to a fresh ClientProtocol, until the protocol ends the connection. The
// frames themselves (beast's WebSocket framing) are Boost's, fuzzed there.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz/protocol_harness.h"
#include "server/transport/http/json_envelope.h"

namespace {

using sim4cv::session::ClientProtocol;

}  // namespace

// ASan stores each allocation's stack (malloc_context_size, 30 frames by
// default) in its stack depot. Most of this target's allocations are made in
// protobuf's JSON code, a system library built without frame pointers, so the
// fast unwinder reads junk from the third frame on and nearly every stack is
// new: the depot's lookups were half of the run's time and its growth 300 MB.
// Two frames (the allocator and its caller, which is all that is sound here)
// keep every check: an error report still unwinds the faulting access in full,
// and LeakSanitizer still reports leaks (with 0 or 1 frames it silently drops
// them). ASAN_OPTIONS overrides this, e.g. to replay a finding with the
// allocation stacks: ASAN_OPTIONS=malloc_context_size=30.
//
// The same parser makes many small allocations per message, and with ASan's
// default 256 MB quarantine recycling freed chunks took a third of the run's
// time (669 exec/s against 940 with 4 MB, same seed and corpus, 40 s each) and
// 326 MB of memory. A use after free is still caught while the freed chunk is
// among the last 4 MB freed (older ones may be reused by then).
extern "C" const char* __asan_default_options() {
  return "malloc_context_size=2:quarantine_size_mb=4";
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  sim4cv::fuzz::ProtocolHarness& harness = sim4cv::fuzz::SharedHarness();
  sim4cv::fuzz::FuzzSession session(harness.context());
  sim4cv::proto::Envelope request, reply;
  std::string reply_json;
  std::string_view input(reinterpret_cast<const char*>(data), size);
  while (!input.empty()) {
    const std::size_t end = input.find('\n');
    const std::string_view message = input.substr(0, end);
    input = end == std::string_view::npos ? std::string_view() : input.substr(end + 1);
    ClientProtocol::Outcome outcome = ClientProtocol::Outcome::kReply;  // the Error for bad JSON
    if (sim4cv::transport::EnvelopeFromJson(message, request).empty()) {
      outcome = session.protocol.Handle(request, reply);
      if (outcome != ClientProtocol::Outcome::kNoReply) sim4cv::transport::EnvelopeToJson(reply, reply_json);
    }
    harness.DrainCommands();
    if (outcome == ClientProtocol::Outcome::kReplyAndClose) break;
  }
  return 0;
}
