// The C++ client's part of the client benchmark (bench/bench_clients.py runs
// it beside the Python and Octave clients against one daemon):
//   sim4cv_bench_client_cpp --address ADDR [--frames N]
//     lockstep 320x180 RGB frames: frames per second, and latency from render
//     end (Frame.render_end_mono_ns) to the frame in hand;
//   sim4cv_bench_client_cpp --address ADDR --age [--frames N] [--period-ms P]
//     a reader asking for the newest frame every P ms (RequestFrame) of a
//     realtime daemon: the frame's age when it is in hand.
// Prints one JSON line. The daemon is the caller's (bench/bench_clients.py).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "bench/stats.h"
#include "sim4cv/client.h"
#include "sim4cv/shm_client.h"

namespace {

using namespace sim4cv;

double Percentile(std::vector<double> samples, double q) {
  std::sort(samples.begin(), samples.end());
  return samples[static_cast<std::size_t>(q * static_cast<double>(samples.size() - 1))];
}

std::string Transport(const std::string& address) { return address.substr(0, address.find("://")); }

// The camera to subscribe: the ring's over shared memory, else the first.
std::string Camera(Client& client) {
  if (client.shm()) return client.shm()->camera();
  return client.welcome().cameras(0).name();
}

double MicrosecondsSince(int64_t render_end_ns) {
  return static_cast<double>(bench::MonotonicNanoseconds() - render_end_ns) / 1e3;
}

}  // namespace

int main(int argc, char** argv) {
  std::string address;
  int frames = 300;
  int period_ms = 100;
  bool age = false;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--age") {
      age = true;
    } else if (i + 1 < argc && flag == "--address") {
      address = argv[++i];
    } else if (i + 1 < argc && flag == "--frames") {
      frames = std::stoi(argv[++i]);
    } else if (i + 1 < argc && flag == "--period-ms") {
      period_ms = std::stoi(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: %s --address ADDR [--frames N] [--age [--period-ms P]]\n", argv[0]);
      return 2;
    }
  }
  Client client;
  client.Connect(address, "bench-cpp");
  std::vector<double> samples;
  if (age) {
    client.Subscribe(Camera(client), {proto::CHANNEL_RGB}, proto::DELIVERY_ON_REQUEST);
    for (int i = 0; i < frames; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(period_ms));
      const proto::Frame& frame = client.RequestFrame();
      samples.push_back(MicrosecondsSince(frame.render_end_mono_ns()) / 1e3);
    }
    std::printf(
        "{\"language\": \"c++\", \"transport\": \"%s\", \"period_ms\": %d, \"age_median_ms\": %.1f, "
        "\"age_p90_ms\": %.1f, \"age_max_ms\": %.1f, \"frames\": %d}\n",
        Transport(address).c_str(), period_ms, Percentile(samples, 0.5), Percentile(samples, 0.9),
        Percentile(samples, 1.0), frames);
    return 0;
  }
  client.Subscribe(Camera(client), {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
  for (int i = 0; i < 10; ++i) client.StepAndReceive();  // warm-up
  const auto measured = std::chrono::steady_clock::now();
  for (int i = 0; i < frames; ++i) {
    const proto::Frame& frame = client.StepAndReceive();
    if (!FindImage(frame, proto::CHANNEL_RGB)) throw std::runtime_error("a frame without RGB");
    samples.push_back(MicrosecondsSince(frame.render_end_mono_ns()));
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - measured).count();
  std::printf(
      "{\"language\": \"c++\", \"transport\": \"%s\", \"fps\": %.1f, \"latency_median_us\": %.1f, "
      "\"latency_p90_us\": %.1f, \"frames\": %d}\n",
      Transport(address).c_str(), frames / seconds, Percentile(samples, 0.5), Percentile(samples, 0.9), frames);
  return 0;
}
