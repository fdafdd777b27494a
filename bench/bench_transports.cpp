// One latency benchmark for all transports: in one run, on the
// default scene, a lockstep client receives N frames over shared memory, TCP
// and UDP, at 320x180 and 1280x720 RGB; for each: median/p99/max latency from
// render end (Frame.render_end_mono_ns) to the client holding the whole frame,
// frames per second of the lockstep loop, and a small request -> reply round
// trip (GetState -> State). For comparison, the time of one memcpy of the
// frame's RGB bytes on this machine: the floor. Shared memory runs twice: with
// the ring carrying only RGB (--shm-channels rgb, what this client reads) and
// with the default ring of all three channels. The renderer reads the ring's
// channels straight into its slot, so the ring copies nothing; the
// bare cross-process futex wake-up, measured in the same run, is the floor.
//   sim4cv_bench_transports [--frames N] [--frames-large N]
#include <sys/mman.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "bench/stats.h"
#include "protocol/shm_sync.h"
#include "sim4cv/client.h"
#include "sim4cv/shm_client.h"
#include "sim4cv/udp_client.h"
#include "tests/support/daemon_process.h"

namespace {

using namespace sim4cv;
using Clock = std::chrono::steady_clock;


struct Result {
  bench::Summary latency_us;
  double fps = 0;
  bench::Summary round_trip_us;
};

// Runs `frames` lockstep iterations of `step_and_hold` (which returns the
// frame's render_end_mono_ns once the client holds it) and `requests` round trips.
Result Measure(int frames, const std::function<int64_t()>& step_and_hold, const std::function<void()>& round_trip) {
  for (int i = 0; i < 50; ++i) step_and_hold();  // warm buffers on both sides
  std::vector<double> latency;
  latency.reserve(static_cast<std::size_t>(frames));
  const auto start = Clock::now();
  for (int i = 0; i < frames; ++i) {
    const int64_t rendered = step_and_hold();
    latency.push_back(static_cast<double>(bench::MonotonicNanoseconds() - rendered) / 1e3);
  }
  Result result;
  result.fps = frames / std::chrono::duration<double>(Clock::now() - start).count();
  result.latency_us = bench::Summarize(std::move(latency));
  std::vector<double> trips;
  for (int i = 0; i < 1000; ++i) {
    const int64_t before = bench::MonotonicNanoseconds();
    round_trip();
    trips.push_back(static_cast<double>(bench::MonotonicNanoseconds() - before) / 1e3);
  }
  result.round_trip_us = bench::Summarize(std::move(trips));
  return result;
}

std::vector<std::string> DaemonArgs(const std::string& width, const std::string& height) {
  return {"--width", width, "--height", height, "--log-level", "warning"};
}

Result OverTcp(const std::string& w, const std::string& h, int frames) {
  testing::DaemonProcess daemon(DaemonArgs(w, h));
  Client client;
  client.Connect("127.0.0.1", daemon.tcp_port(), "bench-tcp");
  client.Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
  const Result r = Measure(
      frames, [&] { return client.StepAndReceive().render_end_mono_ns(); }, [&] { client.GetState(); });
  client.Close();
  daemon.Stop();
  return r;
}

Result OverUdp(const std::string& w, const std::string& h, int frames) {
  testing::DaemonProcess daemon(DaemonArgs(w, h));
  UdpClient client;
  client.Connect("127.0.0.1", static_cast<uint16_t>(std::stoi(testing::ListeningField(daemon.listening_line(), "udp"))),
                 "bench-udp");
  client.Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
  proto::Frame frame;
  const Result r = Measure(
      frames,
      [&] {
        client.Step();
        if (!client.ReceiveFrame(frame, std::chrono::milliseconds(5000))) throw std::runtime_error("UDP frame lost");
        return frame.render_end_mono_ns();
      },
      [&] { client.GetState(); });
  client.Close();
  daemon.Stop();
  return r;
}

// `channels`: the daemon's --shm-channels, what the ring writer copies per frame.
Result OverShm(const std::string& w, const std::string& h, int frames, const std::string& channels) {
  const std::string name = "/sim4cv-bench-" + std::to_string(getpid());
  auto args = DaemonArgs(w, h);
  args.insert(args.end(), {"--shm-name", name, "--shm-channels", channels});
  testing::DaemonProcess daemon(args);
  ShmClient client;
  client.Open(name);
  client.Hello("bench-shm");
  client.Subscribe(proto::DELIVERY_LOCKSTEP, {proto::CHANNEL_RGB});
  FrameView view;
  uint64_t last = client.newest_frame_id();
  const Result r = Measure(
      frames,
      [&] {
        client.Step();
        if (!client.WaitForFrame(last, std::chrono::milliseconds(5000))) throw std::runtime_error("no shm frame");
        // Holding the frame = a validated zero-copy view of the newest slot.
        if (!client.AcquireNewest(view)) throw std::runtime_error("no shm view");
        last = view.frame_id();
        const int64_t rendered = view.render_end_mono_ns();
        view.Release();
        return rendered;
      },
      [&] { client.GetState(); });
  client.Close();
  daemon.Stop();
  return r;
}

// The bare cross-process futex wake-up, measured in the same run as the
// transports: a child process sleeps on a word in shared memory; the parent
// stamps CLOCK_MONOTONIC, bumps the word and wakes it, as the ring writer
// does; the child records how long after the stamp it ran. This is what
// shared-memory delivery cannot go below (the target: within 3 us of it).
// `gap`: how long the reader sleeps before each wake; on a VM a vCPU idle for
// long is halted by the hypervisor and takes longer to wake, so the floor is
// measured with the gap between frames of the run it is compared with.
bench::Summary FutexWakeFloorUs(int samples, std::chrono::microseconds gap) {
  struct Shared {
    uint32_t word;
    int64_t stamp_ns;
    double us[20000];
  };
  samples = std::min(samples, 20000);
  auto* shared = static_cast<Shared*>(
      mmap(nullptr, sizeof(Shared), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0));
  if (shared == MAP_FAILED) throw std::runtime_error("mmap for the futex floor failed");
  shared->word = 0;
  const pid_t child = fork();
  if (child == 0) {
    for (uint32_t seen = 0; seen < static_cast<uint32_t>(samples);) {
      shm::FutexWait(shared->word, seen, 1'000'000'000);
      const uint32_t now = shm::Atomic(shared->word).load(std::memory_order_acquire);
      if (now == seen) continue;
      shared->us[now - 1] = static_cast<double>(bench::MonotonicNanoseconds() - shared->stamp_ns) / 1e3;
      seen = now;
    }
    _exit(0);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  for (int i = 1; i <= samples; ++i) {
    std::this_thread::sleep_for(gap);  // the reader is asleep, as between frames
    shared->stamp_ns = bench::MonotonicNanoseconds();
    shm::Atomic(shared->word).store(static_cast<uint32_t>(i), std::memory_order_seq_cst);
    shm::FutexWake(shared->word, 0x7fffffff);
  }
  waitpid(child, nullptr, 0);
  const bench::Summary result = bench::Summarize(std::vector<double>(shared->us, shared->us + samples));
  munmap(shared, sizeof(Shared));
  return result;
}

double MemcpyFloorUs(std::size_t bytes) {
  std::vector<uint8_t> from(bytes, 7), to(bytes);
  std::vector<double> us;
  for (int i = 0; i < 2000; ++i) {
    from[static_cast<std::size_t>(i) % bytes] = static_cast<uint8_t>(i);  // keep the copy from being elided
    const int64_t before = bench::MonotonicNanoseconds();
    std::memcpy(to.data(), from.data(), bytes);
    us.push_back(static_cast<double>(bench::MonotonicNanoseconds() - before) / 1e3);
  }
  volatile uint8_t sink = to[bytes / 2];
  (void)sink;
  return bench::Summarize(us).median;
}

void Print(const char* transport, const Result& r) {
  std::printf("| %-20s | %8.1f | %8.1f | %8.1f | %6.0f | %8.1f | %8.1f |\n", transport, r.latency_us.median,
              r.latency_us.p99, r.latency_us.max, r.fps, r.round_trip_us.median, r.round_trip_us.p99);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 10000, frames_large = 1000;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::string(argv[i]) == "--frames") frames = std::stoi(argv[i + 1]);
    if (std::string(argv[i]) == "--frames-large") frames_large = std::stoi(argv[i + 1]);
  }
  for (const auto& [w, h, n] : {std::tuple<std::string, std::string, int>{"320", "180", frames},
                                {"1280", "720", frames_large}}) {
    const std::size_t rgb_bytes = static_cast<std::size_t>(std::stoi(w)) * std::stoi(h) * 3;
    // The ring writer's copy is part of the shm latency: RGB alone (3 bytes a
    // pixel) with --shm-channels rgb, RGB + depth + mask (9 bytes) by default.
    std::printf(
        "\n%sx%s RGB, %d lockstep frames per transport; memcpy floor of %zu bytes (RGB): median %.1f us; "
        "of %zu bytes (RGB+depth+mask, what the default ring writer copies): median %.1f us\n",
        w.c_str(), h.c_str(), n, rgb_bytes, MemcpyFloorUs(rgb_bytes), rgb_bytes * 3, MemcpyFloorUs(rgb_bytes * 3));
    std::printf("| via | median us | p99 us | max us | fps | GetState rtt median us | rtt p99 us |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    const Result shm_rgb = OverShm(w, h, n, "rgb");
    const auto frame_gap = std::chrono::microseconds(static_cast<int64_t>(1e6 / shm_rgb.fps));
    for (const auto gap : {std::chrono::microseconds(300), frame_gap}) {
      const bench::Summary wake = FutexWakeFloorUs(std::min(n, 2000), gap);
      const std::string label = "futex wake, " + std::to_string(gap.count()) + " us idle";
      std::printf("| %-20s | %8.1f | %8.1f | %8.1f | %6s | %8s | %8s |\n", label.c_str(), wake.median, wake.p99,
                  wake.max, "-", "-", "-");
    }
    Print("shm, ring rgb", shm_rgb);
    Print("shm, ring rgb+d+m", OverShm(w, h, n, "rgb,depth,mask"));
    Print("tcp", OverTcp(w, h, n));
    Print("udp", OverUdp(w, h, n));
  }
  return 0;
}
