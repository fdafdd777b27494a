// Wake-up and round-trip latency of the shared-memory transport, to choose
// its wait mechanism (figures in docs/benchmarks.md):
//   1. frame wake: a writer thread publishes a small frame at random 0.5-2 ms
//      gaps; a reader in WaitForFrame measures publish -> awake, for several
//      client spin lengths (0 = futex only), with the reader's CPU use;
//   2. against the real daemon: GetState round trip over shm (request ring +
//      doorbell, response ring + futex) and over TCP, and lockstep Step ->
//      frame over shm and over TCP.
//   sim4cv_bench_shm_latency [--samples N] [--width W --height H]
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "bench/stats.h"
#include "server/session/counters.h"
#include "server/transport/shm/shm_ring_writer.h"
#include "sim4cv/shm_client.h"
#include "tests/support/daemon_process.h"

namespace {

using namespace sim4cv;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;


double ThreadCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_THREAD, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) / 1e6;
}

std::shared_ptr<transport::ShmRegion> MakeRegion() {
  transport::ShmRegionParams p;
  p.camera_name = "uav";
  p.width = 16;
  p.height = 16;
  p.slot_count = 4;
  return std::make_shared<transport::ShmRegion>(p);
}

void Print(const char* what, const std::vector<double>& us, const std::string& extra = "") {
  const auto s = bench::Summarize(us);
  std::printf("%-58s median %7.1f us  p99 %8.1f us  max %8.1f us%s\n", what, s.median, s.p99, s.max, extra.c_str());
}

void FrameWake(int samples, std::chrono::microseconds spin) {
  auto region = MakeRegion();
  transport::ShmRingWriter writer(region, 0);
  ShmClient client;
  client.OpenFrames(region->fd());  // read-only, as a client attached through the socket maps it
  client.set_spin(spin);
  std::thread publisher([&] {
    std::mt19937 random(7);
    std::uniform_int_distribution<int> gap_us(500, 2000);
    session::Frame frame;
    frame.width = frame.height = 16;
    for (const auto& info : channels::kPixelChannels) frame.Hold(info.id);
    for (int i = 1; i <= samples; ++i) {
      std::this_thread::sleep_for(std::chrono::microseconds(gap_us(random)));
      frame.frame_id = static_cast<uint64_t>(i);
      frame.render_end_mono_ns = bench::MonotonicNanoseconds();
      writer.Write(frame);
    }
  });
  std::vector<double> us;
  const double cpu_before = ThreadCpuSeconds();
  const auto start = Clock::now();
  for (uint64_t last = 0; last < static_cast<uint64_t>(samples);) {
    if (!client.WaitForFrame(last, 1000ms)) break;
    const int64_t awake = bench::MonotonicNanoseconds();
    FrameView view;
    client.AcquireNewest(view);
    if (view.frame_id() == last + 1) us.push_back(static_cast<double>(awake - view.render_end_mono_ns()) / 1e3);
    last = view.frame_id();
  }
  const double cpu = (ThreadCpuSeconds() - cpu_before) / std::chrono::duration<double>(Clock::now() - start).count();
  publisher.join();
  char label[96], extra[64];
  std::snprintf(label, sizeof label, "frame wake, reader spin %5lld us", static_cast<long long>(spin.count()));
  std::snprintf(extra, sizeof extra, "  reader CPU %4.0f%%", cpu * 100);
  Print(label, us, extra);
}

void AgainstDaemon(int samples, const std::string& width, const std::string& height) {
  const std::string name = "/sim4cv-bench-daemon-" + std::to_string(getpid());
  const std::vector<std::string> size = {"--width", width, "--height", height, "--log-level", "warning"};
  std::vector<std::string> args = size;
  args.insert(args.end(), {"--shm-name", name});
  testing::DaemonProcess daemon(args);
  ShmClient shm;
  shm.Open(name);
  shm.Hello("bench");
  Client tcp;
  tcp.Connect("127.0.0.1", daemon.tcp_port(), "bench");
  std::vector<double> shm_us, tcp_us;
  for (int i = 0; i < samples; ++i) {
    auto start = Clock::now();
    shm.GetState();
    shm_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - start).count());
    start = Clock::now();
    tcp.GetState();
    tcp_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - start).count());
  }
  Print("real daemon: GetState round trip over shm", shm_us);
  Print("real daemon: GetState round trip over TCP", tcp_us);

  // Lockstep: Step -> whole frame available (includes physics and rendering).
  shm.Subscribe(proto::DELIVERY_LOCKSTEP);
  std::vector<double> step_us, view_us, copy_us;
  OwnedFrame frame;
  FrameView view;
  uint64_t last = 0;
  const std::string label = "real daemon " + width + "x" + height + ": ";
  for (int i = 0; i < samples / 4; ++i) {
    const auto start = Clock::now();
    shm.Step();
    if (!shm.WaitForFrame(last, 5000ms)) break;
    shm.AcquireNewest(view);
    view_us.push_back(static_cast<double>(bench::MonotonicNanoseconds() - view.render_end_mono_ns()) / 1e3);
    shm.ReadNewest(frame);
    copy_us.push_back(static_cast<double>(bench::MonotonicNanoseconds() - frame.render_end_mono_ns) / 1e3);
    last = frame.frame_id;
    step_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - start).count());
  }
  Print((label + "render end -> zero-copy view, shm").c_str(), view_us);
  Print((label + "render end -> frame copied out, shm").c_str(), copy_us);
  Print((label + "Step -> frame copied out, shm lockstep").c_str(), step_us);
  tcp.Close();
  shm.Close();
  daemon.Stop();

  testing::DaemonProcess tcp_daemon(size);
  Client tcp_only;
  tcp_only.Connect("127.0.0.1", tcp_daemon.tcp_port(), "bench");
  tcp_only.Subscribe("uav", {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_MASK, proto::CHANNEL_BOXES},
                     proto::DELIVERY_LOCKSTEP);
  step_us.clear();
  copy_us.clear();
  for (int i = 0; i < samples / 4; ++i) {
    const auto start = Clock::now();
    const proto::Frame& received = tcp_only.StepAndReceive();
    copy_us.push_back(static_cast<double>(bench::MonotonicNanoseconds() - received.render_end_mono_ns()) / 1e3);
    step_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - start).count());
  }
  Print((label + "render end -> frame received, TCP").c_str(), copy_us);
  Print((label + "Step -> frame received, TCP lockstep").c_str(), step_us);
}

}  // namespace

int main(int argc, char** argv) {
  int samples = 2000;
  std::string width = "320", height = "180";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--samples") samples = std::stoi(argv[i + 1]);
    if (flag == "--width") width = argv[i + 1];
    if (flag == "--height") height = argv[i + 1];
  }
  for (auto spin : {0us, 20us, 100us, 3000us}) FrameWake(samples, spin);
  AgainstDaemon(samples, width, height);
  return 0;
}
