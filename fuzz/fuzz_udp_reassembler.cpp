// Fuzz target: the C++ client's UDP receive path (clients/cpp/src/udp), as
// UdpClient takes datagrams: ClassifyDatagram reads the top level of each
// without copying; a FrameChunk goes to the FrameReassembler, and a frame it
// completes is parsed as an Envelope; anything else is parsed as an Envelope.
// The input is a series of datagrams (records, fuzz_input.h) from a daemon,
// or from anyone who can send to the client's port.
#include <cstddef>
#include <cstdint>

#include "clients/cpp/src/udp/frame_reassembler.h"
#include "fuzz/fuzz_input.h"
#include "protocol/framing.h"
#include "sim4cv.pb.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  using sim4cv::detail::FrameReassembler;
  // What UdpClient uses: the protocol's default message bound.
  FrameReassembler reassembler(sim4cv::wire::kDefaultMaxMessageBytes);
  sim4cv::proto::Envelope envelope;
  for (std::string_view record : sim4cv::fuzz::SplitRecords(data, size)) {
    const auto* bytes = reinterpret_cast<const uint8_t*>(record.data());
    sim4cv::detail::ChunkView chunk;
    switch (sim4cv::detail::ClassifyDatagram(bytes, record.size(), chunk)) {
      case sim4cv::detail::DatagramKind::kChunk:
        if (reassembler.Add(chunk) == FrameReassembler::Result::kComplete) {
          const std::string_view frame = reassembler.frame();
          (void)envelope.ParseFromArray(frame.data(), static_cast<int>(frame.size()));
        }
        break;
      case sim4cv::detail::DatagramKind::kOther:
        (void)envelope.ParseFromArray(bytes, static_cast<int>(record.size()));
        break;
      case sim4cv::detail::DatagramKind::kMalformed: break;
    }
  }
  return 0;
}
