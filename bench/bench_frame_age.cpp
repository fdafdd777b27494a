// How old a frame is when a slow reader gets it: a tracker that wants a
// frame every 100 ms from a 30 Hz stream (320x180 RGB + depth + mask +
// boxes), over each transport and delivery, against the real daemon in
// realtime mode. Age: from the end of rendering (Frame.render_end_mono_ns,
// CLOCK_MONOTONIC of the same host) to the whole frame in the reader's hands.
//   sim4cv_bench_frame_age [--reads N] [--period-ms P]
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "bench/stats.h"
#include "sim4cv/client.h"
#include "sim4cv/shm_client.h"
#include "sim4cv/udp_client.h"
#include "tests/support/daemon_process.h"

namespace {

using namespace sim4cv;
using Ms = std::chrono::milliseconds;

const std::vector<proto::Channel> kChannels = {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_MASK,
                                               proto::CHANNEL_BOXES};

// `read` returns the render end of the frame it got.
template <typename Read>
void Measure(const char* name, int reads, Ms period, Read read) {
  std::vector<double> ages_ms;
  for (int i = 0; i < reads; ++i) {
    std::this_thread::sleep_for(period);
    const int64_t render_end = read();
    ages_ms.push_back(static_cast<double>(bench::MonotonicNanoseconds() - render_end) / 1e6);
  }
  const bench::Summary s = bench::Summarize(ages_ms);
  std::printf("%-28s %d reads: frame age median %6.1f ms, p99 %6.1f ms, max %6.1f ms\n", name, reads, s.median, s.p99,
              s.max);
}

}  // namespace

int main(int argc, char** argv) {
  int reads = 100;
  Ms period(100);
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--reads") reads = std::stoi(argv[i + 1]);
    if (flag == "--period-ms") period = Ms(std::stoi(argv[i + 1]));
  }
  const std::string shm_name = "/sim4cv-bench-age-" + std::to_string(::getpid());
  testing::DaemonProcess daemon({"--mode", "realtime", "--frame-hz", "30", "--shm-name", shm_name, "--shm-channels",
                                 "rgb,depth,mask", "--log-level", "warning"});
  std::printf("reader every %lld ms, daemon at 30 Hz (33 ms a frame), 320x180\n",
              static_cast<long long>(period.count()));

  Client tcp;
  tcp.Connect("127.0.0.1", daemon.tcp_port(), "age-tcp");
  tcp.Subscribe("uav", kChannels, proto::DELIVERY_NEWEST);
  proto::Frame frame;
  Measure("tcp newest (pushed)", reads, period, [&] {
    tcp.ReceiveFrame(frame, Ms(5000));
    return frame.render_end_mono_ns();
  });
  tcp.Subscribe("uav", kChannels, proto::DELIVERY_ON_REQUEST);
  Measure("tcp on request", reads, period, [&] { return tcp.RequestFrame(Ms(5000)).render_end_mono_ns(); });
  tcp.Close();

  UdpClient udp;
  udp.Connect("127.0.0.1", static_cast<uint16_t>(std::stoi(testing::ListeningField(daemon.listening_line(), "udp"))),
              "age-udp");
  udp.Subscribe("uav", kChannels, proto::DELIVERY_ON_REQUEST);
  Measure("udp on request", reads, period, [&] {
    udp.RequestFrame(frame, Ms(5000));
    return frame.render_end_mono_ns();
  });
  udp.Close();

  ShmClient shm;
  shm.Open(shm_name);
  OwnedFrame owned;
  Measure("shm newest slot (copy)", reads, period, [&] {
    shm.ReadNewest(owned);
    return owned.render_end_mono_ns;
  });
  shm.Close();
  return daemon.Stop() == 0 ? 0 : 1;
}
