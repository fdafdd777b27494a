// Frames per second delivered over UDP to one lockstep client, latency from
// the end of rendering (Frame.render_end_mono_ns) to the client holding the
// whole reassembled frame, and the round trip of a small request (GetState ->
// State), against the real daemon started as a separate process.
//   sim4cv_bench_udp_delivery [--frames N] [--width W] [--height H] [--channels rgb|all] [--datagram-bytes N]
#include <time.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/stats.h"
#include "sim4cv/udp_client.h"
#include "tests/support/daemon_process.h"

namespace {


}  // namespace

int main(int argc, char** argv) {
  std::string width = "320", height = "180", channels = "rgb", datagram_bytes = "65000";
  int frames = 3000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--frames") frames = std::stoi(argv[i + 1]);
    if (flag == "--width") width = argv[i + 1];
    if (flag == "--height") height = argv[i + 1];
    if (flag == "--channels") channels = argv[i + 1];
    if (flag == "--datagram-bytes") datagram_bytes = argv[i + 1];
  }
  using namespace sim4cv;
  testing::DaemonProcess daemon(
      {"--width", width, "--height", height, "--udp-datagram-bytes", datagram_bytes, "--log-level", "warning"});
  UdpClient client;
  client.Connect("127.0.0.1", static_cast<uint16_t>(std::stoi(testing::ListeningField(daemon.listening_line(), "udp"))),
                 "bench");
  std::vector<proto::Channel> wanted = {proto::CHANNEL_RGB};
  if (channels == "all") wanted = {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_MASK, proto::CHANNEL_BOXES};
  client.Subscribe("uav", wanted, proto::DELIVERY_LOCKSTEP);
  proto::Frame frame;
  auto step = [&] {
    client.Step();
    if (!client.ReceiveFrame(frame, std::chrono::milliseconds(2000))) {
      std::fprintf(stderr, "a frame was lost; stepping again\n");
      return false;
    }
    return true;
  };
  for (int i = 0; i < 50; ++i) step();  // warm up buffers on both sides

  std::vector<double> latency_us;
  latency_us.reserve(static_cast<std::size_t>(frames));
  std::size_t bytes = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < frames; ++i) {
    if (!step()) continue;
    latency_us.push_back(static_cast<double>(bench::MonotonicNanoseconds() - frame.render_end_mono_ns()) / 1e3);
    for (const auto& image : frame.images()) bytes += image.data().size();
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<double> round_trip_us;
  for (int i = 0; i < 1000; ++i) {
    const auto before = std::chrono::steady_clock::now();
    client.GetState();
    round_trip_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - before).count());
  }
  const auto s = bench::Summarize(latency_us);
  const auto r = bench::Summarize(round_trip_us);
  std::printf("udp lockstep %sx%s channels=%s datagrams<=%s: %zu frames, %.0f fps, %.1f KB/frame; render-end -> "
              "client latency: median %.0f us, p99 %.0f us, max %.0f us; lost frames %llu; GetState round trip: "
              "median %.0f us, p99 %.0f us\n",
              width.c_str(), height.c_str(), channels.c_str(), datagram_bytes.c_str(), latency_us.size(),
              static_cast<double>(latency_us.size()) / seconds,
              static_cast<double>(bytes) / static_cast<double>(latency_us.size()) / 1024.0, s.median, s.p99, s.max,
              static_cast<unsigned long long>(client.frames_dropped_incomplete()), r.median, r.p99);
  client.Close();
  return daemon.Stop() == 0 ? 0 : 1;
}
