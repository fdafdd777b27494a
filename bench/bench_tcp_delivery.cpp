// Frames per second delivered over TCP to one lockstep client, and latency
// from the end of rendering (Frame.render_end_mono_ns) to the client holding
// the whole frame, against the real daemon started as a separate process.
//   sim4cv_bench_tcp_delivery --daemon PATH [--frames N] [--width W] [--height H] [--channels rgb|all]
#include <time.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/stats.h"
#include "sim4cv/client.h"
#include "tests/support/daemon_process.h"

namespace {


}  // namespace

int main(int argc, char** argv) {
  std::string width = "320", height = "180", channels = "all";
  int frames = 3000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--frames") frames = std::stoi(argv[i + 1]);
    if (flag == "--width") width = argv[i + 1];
    if (flag == "--height") height = argv[i + 1];
    if (flag == "--channels") channels = argv[i + 1];
  }
  using namespace sim4cv;
  testing::DaemonProcess daemon({"--width", width, "--height", height, "--log-level", "warning"});
  Client client;
  client.Connect("127.0.0.1", daemon.tcp_port(), "bench");
  std::vector<proto::Channel> wanted = {proto::CHANNEL_RGB};
  if (channels == "all") wanted = {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_MASK, proto::CHANNEL_BOXES};
  client.Subscribe("uav", wanted, proto::DELIVERY_LOCKSTEP);
  for (int i = 0; i < 50; ++i) client.StepAndReceive();  // warm up buffers on both sides

  std::vector<double> latency_us;
  latency_us.reserve(static_cast<std::size_t>(frames));
  std::size_t bytes = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < frames; ++i) {
    const proto::Frame& frame = client.StepAndReceive();
    latency_us.push_back(static_cast<double>(bench::MonotonicNanoseconds() - frame.render_end_mono_ns()) / 1e3);
    for (const auto& image : frame.images()) bytes += image.data().size();
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto s = bench::Summarize(latency_us);
  std::printf("tcp lockstep %sx%s channels=%s: %d frames, %.0f fps, %.1f KB/frame; render-end -> client latency: "
              "median %.0f us, p99 %.0f us, max %.0f us\n",
              width.c_str(), height.c_str(), channels.c_str(), frames, frames / seconds,
              static_cast<double>(bytes) / frames / 1024.0, s.median, s.p99, s.max);
  client.Close();
  return daemon.Stop() == 0 ? 0 : 1;
}
