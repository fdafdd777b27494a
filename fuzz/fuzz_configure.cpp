// Fuzz target: the Configure checks (server/session/configure_check.cpp). The
// input is a serialized proto::Configure, as it arrives inside an Envelope;
// CheckConfigure answers "" or what is wrong, and must do so for any fields
// (huge counts, lengths, non-finite numbers) without throwing or building
// anything in proportion to a refused value.
#include <cstddef>
#include <cstdint>
#include <string>

#include "server/common/limits.h"
#include "server/session/configure_check.h"

// Longer than any message the checks write with names quoted shortened
// (limits::kQuotedBytes each): a longer one echoes what the client sent.
constexpr std::size_t kMaxProblemBytes = 1024;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  sim4cv::proto::Configure request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return 0;
  const std::string problem = sim4cv::session::CheckConfigure(request);
  // The answer goes into an Error: it quotes names shortened, never in full.
  if (problem.size() > kMaxProblemBytes) __builtin_trap();
  return 0;
}
