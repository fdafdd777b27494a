// Soak test: N clients (default 8) for a chosen time (default 30
// minutes) connect over TCP, UDP and shared memory, subscribe (lockstep and
// newest, all channels), configure the world (spawn/remove entities,
// add/remove cameras, load maps by name) and leave abruptly, some in the
// middle of a message, while the daemon's RSS and open descriptors are
// sampled. It reports the growth and the lockstep frames lost (a client that
// Stepped and got no frame before its deadline), and exits 1 if a target is
// missed: RSS growth over 5% after warm-up, any descriptor growth, any lost
// lockstep frame (docs/benchmarks.md, "Soak").
//
// RSS and descriptors are compared at two checkpoints, after the warm-up
// (the first 10%) and at the end, taken the same way: every client paused
// and gone, the same map loaded, the frame pool's trim period waited out.
//
//   sim4cv_soak [--seconds 1800] [--clients 8] [--seed 1] [--deadline-ms 20000]
//   sim4cv_soak --port TCP --udp-port UDP --shm-name NAME --pid PID   (a daemon started by hand
//               with --shm-name NAME; lockstep mode)
// Only the public client classes (clients/cpp) and the daemon's flags are used.
#include <dirent.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "sim4cv/client.h"
#include "sim4cv/shm_client.h"
#include "sim4cv/udp_client.h"
#include "tests/support/daemon_process.h"

namespace {

using namespace sim4cv;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using Ms = std::chrono::milliseconds;

const std::vector<proto::Channel> kAllChannels = {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_MASK,
                                                 proto::CHANNEL_BOXES};
const std::vector<std::string> kMaps = {"tracking/easy_urban", "tracking/easy_desert", "driving/train/01_urban"};
const char* const kCheckpointMap = "tracking/easy_urban";

struct Options {
  int seconds = 1800, clients = 8, sample_seconds = 5, deadline_ms = 20000;
  unsigned seed = 1;
  uint16_t port = 0, udp_port = 0;  // 0: start our own daemon
  std::string shm_name;
  pid_t pid = 0;
  std::string only;  // comma-separated session kinds; empty: all
};

enum Kind { kTcpLockstep, kTcpNewest, kUdpLockstep, kUdpNewest, kShmLockstep, kShmNewest, kConfigure, kLoadMap,
            kHalfMessage, kKinds };
const char* const kKindNames[kKinds] = {"tcp-lockstep", "tcp-newest", "udp-lockstep", "udp-newest", "shm-lockstep",
                                        "shm-newest",   "configure",  "load-map",     "half-message"};
const int kWeights[kKinds] = {4, 2, 3, 2, 3, 2, 3, 1, 2};

std::vector<int> Weights(const std::string& only) {
  std::vector<int> weights(std::begin(kWeights), std::end(kWeights));
  if (only.empty()) return weights;
  for (int k = 0; k < kKinds; ++k) {
    if (("," + only + ",").find(std::string(",") + kKindNames[k] + ",") == std::string::npos) weights[k] = 0;
  }
  return weights;
}

struct Counters {
  std::atomic<uint64_t> sessions[kKinds] = {};
  std::atomic<uint64_t> lockstep_frames{0}, newest_frames{0}, lost_lockstep{0}, udp_incomplete{0};
  std::atomic<uint64_t> refused{0}, connection_errors{0}, other_errors{0};
};

// The daemon's resident memory and descriptors, from /proc.
std::size_t RssBytes(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stoull(line.substr(6)) * 1024;
  }
  return 0;
}
int OpenFds(pid_t pid) {
  DIR* dir = opendir(("/proc/" + std::to_string(pid) + "/fd").c_str());
  if (!dir) return -1;
  int count = 0;
  while (const dirent* entry = readdir(dir)) count += entry->d_name[0] != '.';
  closedir(dir);
  return count;
}

class Soak {
 public:
  explicit Soak(const Options& options) : options_(options) {}

  // One client's life: a session of a random kind, again and again, pausing
  // when asked (checkpoints) and stopping at the end.
  void Worker(int index) {
    std::mt19937 rng(options_.seed * 7919u + static_cast<unsigned>(index));
    const std::vector<int> weights = Weights(options_.only);
    std::discrete_distribution<int> pick(weights.begin(), weights.end());
    while (true) {
      {
        std::unique_lock lock(mutex_);
        ++idle_;
        changed_.notify_all();
        changed_.wait(lock, [&] { return stop_ || !paused_; });
        --idle_;
        if (stop_) return;
      }
      const Kind kind = static_cast<Kind>(pick(rng));
      try {
        Run(kind, index, rng);
        ++counters_.sessions[kind];
      } catch (const ServerError&) {
        ++counters_.refused;  // e.g. a camera removed or a map loaded by another client meanwhile
      } catch (const ShmError&) {
        ++counters_.refused;
      } catch (const ConnectionError& e) {
        ++counters_.connection_errors;
        Note(kind, e.what());
      } catch (const std::exception& e) {
        ++counters_.other_errors;
        Note(kind, e.what());
      }
    }
  }

  // Pauses every worker until none is in a session.
  void Pause() {
    std::unique_lock lock(mutex_);
    paused_ = true;
    changed_.wait(lock, [&] { return idle_ == options_.clients; });
  }
  void Resume() {
    std::lock_guard lock(mutex_);
    paused_ = false;
    changed_.notify_all();
  }
  void Stop() {
    std::lock_guard lock(mutex_);
    stop_ = true;
    changed_.notify_all();
  }
  bool stopping() {
    std::lock_guard lock(mutex_);
    return stop_ || paused_;
  }

  Counters& counters() { return counters_; }
  std::string host = "127.0.0.1";

 private:
  Ms deadline() const { return Ms(options_.deadline_ms); }

  void Note(Kind kind, const std::string& what) {
    std::lock_guard lock(mutex_);
    if (++notes_ <= 20) std::fprintf(stderr, "soak: %s session: %s\n", kKindNames[kind], what.c_str());
  }

  void Run(Kind kind, int index, std::mt19937& rng) {
    const std::string name = std::string("soak-") + kKindNames[kind] + "-" + std::to_string(index);
    const int length = std::uniform_int_distribution<int>(3, 40)(rng);
    switch (kind) {
      case kTcpLockstep: {
        Client client;
        client.Connect(host, options_.port, name);
        client.Subscribe(client.welcome().cameras(0).name(), kAllChannels, proto::DELIVERY_LOCKSTEP);
        const int depth = std::uniform_int_distribution<int>(1, 3)(rng);  // Steps in flight
        proto::Frame frame;
        for (int i = 0; i < length && !stopping(); i += depth) {
          for (int d = 0; d < depth; ++d) client.Step();
          for (int d = 0; d < depth; ++d) {
            if (!client.ReceiveFrame(frame, deadline())) return Lost(name);
            ++counters_.lockstep_frames;
          }
        }
        if (rng() % 4 == 0) client.Step();  // leaves with a frame coming
        return;
      }
      case kUdpLockstep: {
        // Any datagram may be lost (docs/protocol.md 12): a client that waits
        // too long for its frame Steps again, and the lost frame shows as a
        // gap in frame_id. Counted apart; lost is no frame at all by the deadline.
        UdpClient client;
        client.Connect(host, options_.udp_port, name);
        client.Subscribe(client.welcome().cameras(0).name(), kAllChannels, proto::DELIVERY_LOCKSTEP);
        proto::Frame frame;
        for (int i = 0; i < length && !stopping(); ++i) {
          client.Step();
          const auto give_up = Clock::now() + deadline();
          bool received = false;
          while (!(received = client.ReceiveFrame(frame, 1000ms)) && Clock::now() < give_up) {
            ++counters_.udp_incomplete;
            client.Step();
          }
          if (!received) {
            return Lost(name + " (UDP frames completed " + std::to_string(client.frames_completed()) +
                        ", dropped incomplete " + std::to_string(client.frames_dropped_incomplete()) +
                        ", chunks ignored " + std::to_string(client.chunks_ignored()) + ")");
          }
          ++counters_.lockstep_frames;
        }
        return;
      }
      case kShmLockstep: {
        ShmClient client;
        client.Open(options_.shm_name);
        client.Hello(name);
        client.Subscribe(proto::DELIVERY_LOCKSTEP);
        uint64_t published = Published(client);
        for (int i = 0; i < length && !stopping(); ++i) {
          client.Step();
          if (!WaitForNext(client, published)) return Lost(name);
          published = Published(client);
          ++counters_.lockstep_frames;
        }
        return;
      }
      case kTcpNewest:
      case kUdpNewest:
      case kShmNewest:
        return Newest(kind, name, length, rng);
      case kConfigure:
        return Configure(name, rng);
      case kLoadMap: {
        Client client;
        client.Connect(host, options_.port, name);
        if (rng() % 3 == 0) {
          client.Reset();
        } else {
          client.LoadMapByName(kMaps[rng() % kMaps.size()]);
        }
        return;
      }
      case kHalfMessage:
        return HalfMessage(name, rng);
      case kKinds:
        return;
    }
  }

  // A lockstep shm client's frame: the ring's count of published frames
  // moves on. Not a frame id "newer than" the last: LoadMap and Reset start
  // frame ids from 0 again (docs/protocol.md), and every frame rendered while
  // this client is subscribed in lockstep waited for its Step.
  static uint64_t Published(const ShmClient& client) {
    return __atomic_load_n(&client.header().published, __ATOMIC_ACQUIRE);
  }
  bool WaitForNext(const ShmClient& client, uint64_t published) const {
    const auto give_up = Clock::now() + deadline();
    while (Published(client) == published) {
      // Expired by the daemon (silent past --shm-expiry-ms while lockstep
      // waited for someone else): disconnected, not a lost frame.
      if (!client.attached()) throw ConnectionError("the daemon ended the attachment while the client waited for its frame");
      if (Clock::now() >= give_up) return false;
      client.WaitForFrame(client.newest_frame_id(), 100ms);
    }
    return true;
  }

  void Lost(const std::string& name) {
    ++counters_.lost_lockstep;
    std::lock_guard lock(mutex_);
    std::fprintf(stderr, "soak: %s: no lockstep frame within %d ms of its Step\n", name.c_str(), options_.deadline_ms);
  }

  // Newest-frame delivery reads what comes (nothing, while no lockstep
  // client steps) for a while; then leaves.
  void Newest(Kind kind, const std::string& name, int length, std::mt19937& rng) {
    const auto until = Clock::now() + Ms(100 * length);
    proto::Frame frame;
    if (kind == kShmNewest) {
      ShmClient client;
      client.Open(options_.shm_name);
      client.Hello(name);
      client.Subscribe(proto::DELIVERY_NEWEST);
      OwnedFrame owned;
      for (uint64_t last = 0; Clock::now() < until && !stopping();) {
        if (!client.WaitForFrame(last, 200ms)) continue;
        if (rng() % 2 ? client.ReadNewest(owned) : false) last = owned.frame_id;
        else last = client.newest_frame_id();
        ++counters_.newest_frames;
      }
    } else if (kind == kUdpNewest) {
      UdpClient client;
      client.Connect(host, options_.udp_port, name);
      client.Subscribe(client.welcome().cameras(0).name(), kAllChannels, proto::DELIVERY_NEWEST);
      while (Clock::now() < until && !stopping()) counters_.newest_frames += client.ReceiveFrame(frame, 200ms);
    } else {
      Client client;
      client.Connect(host, options_.port, name);
      client.Subscribe(client.welcome().cameras(0).name(), kAllChannels, proto::DELIVERY_NEWEST);
      while (Clock::now() < until && !stopping()) counters_.newest_frames += client.ReceiveFrame(frame, 200ms);
    }
  }

  // An entity with a camera of its own, watched for a moment, then removed
  // (or left behind by a client that just goes: the next LoadMap clears it).
  void Configure(const std::string& name, std::mt19937& rng) {
    Client client;
    client.Connect(host, options_.port, name);
    const std::string entity = name + "-" + std::to_string(++spawned_);
    const bool uav = rng() % 3 != 0;
    const uint32_t id = uav ? client.Spawn(proto::ENTITY_KIND_UAV, entity, -40, -60, 20, 90)
                            : client.Spawn(proto::ENTITY_KIND_CAR, entity, -20, -42, 0, 0);
    const uint32_t width = 16 * std::uniform_int_distribution<uint32_t>(4, 40)(rng);
    const std::string camera = entity + "-cam";
    client.AddCamera({.name = camera, .mounted_on = entity, .width = width, .height = width * 9 / 16});
    // Newest: a lockstep subscriber here would hold every lockstep client back while this one configures.
    client.Subscribe(camera, kAllChannels, proto::DELIVERY_NEWEST);
    proto::Frame frame;
    for (int i = 0; i < 5 && !stopping(); ++i) counters_.newest_frames += client.ReceiveFrame(frame, 100ms);
    if (rng() % 4 == 0) return;  // gone without cleaning up
    client.GetWorld();
    if (rng() % 2) client.RemoveCamera(camera);
    client.Remove(id);
  }

  // A message cut off in the middle, on a raw connection or after the
  // handshake, and the connection closed.
  void HalfMessage(const std::string& name, std::mt19937& rng) {
    Client client;
    proto::Envelope envelope;
    if (rng() % 2) {
      client.ConnectRaw(host, options_.port);
      envelope.mutable_hello()->set_client_name(name);
      envelope.mutable_hello()->set_protocol_version(wire::kProtocolVersion);
    } else {
      client.Connect(host, options_.port, name);
      envelope.mutable_configure()->set_request_id(1);
      envelope.mutable_configure()->mutable_spawn()->set_name(name + std::string(200, 'x'));
    }
    const std::string body = envelope.SerializeAsString();
    std::string bytes(wire::kLengthPrefixBytes, '\0');
    wire::EncodeLengthPrefix(static_cast<uint32_t>(body.size()), reinterpret_cast<uint8_t*>(bytes.data()));
    bytes += body.substr(0, body.size() / 2);
    const std::size_t cut = std::uniform_int_distribution<std::size_t>(1, bytes.size())(rng);
    client.SendRaw(bytes.data(), cut);
    client.Close();
  }

  const Options options_;
  Counters counters_;
  std::mutex mutex_;
  std::condition_variable changed_;
  int idle_ = 0;
  bool paused_ = false, stop_ = false;
  int notes_ = 0;
  std::atomic<uint64_t> spawned_{0};
};

struct Sample {
  double seconds = 0;
  std::size_t rss = 0;
  int fds = 0;
};

// Every client gone and the same map loaded, the frame pool's trim waited
// out: a state that is the same whenever it is taken.
Sample Checkpoint(Soak& soak, const Options& options, double at_seconds, int baseline_fds) {
  soak.Pause();
  Client client;
  client.Connect(soak.host, options.port, "soak-checkpoint");
  client.LoadMapByName(kCheckpointMap);
  client.Close();
  // UDP and shm clients that just went are forgotten after their expiry.
  const auto settle = Clock::now() + 20s;
  while (OpenFds(options.pid) > baseline_fds && Clock::now() < settle) std::this_thread::sleep_for(200ms);
  std::this_thread::sleep_for(3s);  // two trim periods
  Sample sample{at_seconds, RssBytes(options.pid), OpenFds(options.pid)};
  soak.Resume();
  return sample;
}

bool Parse(int argc, char** argv, Options& o) {
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i], value = argv[i + 1];
    if (flag == "--seconds") o.seconds = std::stoi(value);
    else if (flag == "--clients") o.clients = std::stoi(value);
    else if (flag == "--seed") o.seed = static_cast<unsigned>(std::stoul(value));
    else if (flag == "--sample-seconds") o.sample_seconds = std::stoi(value);
    else if (flag == "--deadline-ms") o.deadline_ms = std::stoi(value);
    else if (flag == "--port") o.port = static_cast<uint16_t>(std::stoi(value));
    else if (flag == "--udp-port") o.udp_port = static_cast<uint16_t>(std::stoi(value));
    else if (flag == "--shm-name") o.shm_name = value;
    else if (flag == "--pid") o.pid = static_cast<pid_t>(std::stoi(value));
    else if (flag == "--only") o.only = value;
    else return false;
  }
  return argc % 2 == 1 && o.seconds > 0 && o.clients > 0 && o.sample_seconds > 0 &&
         (o.port == 0 || (o.udp_port != 0 && !o.shm_name.empty() && o.pid > 0));
}

}  // namespace

int main(int argc, char** argv) {
  setvbuf(stdout, nullptr, _IOLBF, 0);  // progress lines as they come, also into a file
  Options options;
  if (!Parse(argc, argv, options)) {
    std::fprintf(stderr,
                 "usage: sim4cv_soak [--seconds 1800] [--clients 8] [--seed 1] [--sample-seconds 5] "
                 "[--deadline-ms 20000]\n"
                 "                   [--port TCP --udp-port UDP --shm-name NAME --pid PID]  (attach to a daemon)\n");
    return 2;
  }
  std::unique_ptr<testing::DaemonProcess> daemon;
  if (options.port == 0) {
    options.shm_name = "sim4cv-soak-" + std::to_string(getpid());
    // A UDP client says no goodbye: a lockstep one that left holds every
    // lockstep client back until its --udp-expiry-ms. Under the shm expiry
    // (5000), so that shm clients waiting for that frame (silent meanwhile)
    // are not expired in turn.
    daemon = std::make_unique<testing::DaemonProcess>(std::vector<std::string>{
        "--udp-port", "0", "--shm-name", options.shm_name, "--udp-expiry-ms", "2000"});
    options.port = daemon->tcp_port();
    options.udp_port = static_cast<uint16_t>(std::stoi(testing::ListeningField(daemon->listening_line(), "udp")));
    options.pid = daemon->pid();
  }
  std::printf("soak: %d clients for %d s against pid %d (tcp %u, udp %u, shm %s)\n", options.clients,
              options.seconds, options.pid, options.port, options.udp_port, options.shm_name.c_str());
  const int baseline_fds = OpenFds(options.pid);
  const std::size_t baseline_rss = RssBytes(options.pid);

  Soak soak(options);
  std::vector<std::thread> workers;
  for (int i = 0; i < options.clients; ++i) workers.emplace_back([&soak, i] { soak.Worker(i); });

  const auto start = Clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  const double warmup = options.seconds * 0.1;
  std::vector<Sample> samples;
  Sample warm{}, end{};
  bool warmed = false, daemon_died = false;
  for (auto next = start; elapsed() < options.seconds;) {
    next += std::chrono::seconds(options.sample_seconds);
    std::this_thread::sleep_until(std::min(next, start + std::chrono::seconds(options.seconds)));
    const Sample sample{elapsed(), RssBytes(options.pid), OpenFds(options.pid)};
    if (sample.rss == 0) {
      daemon_died = true;
      break;
    }
    samples.push_back(sample);
    std::printf("soak: %6.0f s  rss %6.1f MiB  fds %3d  sessions %llu  lockstep frames %llu  lost %llu\n",
                sample.seconds, sample.rss / 1048576.0, sample.fds,
                [&] {
                  unsigned long long n = 0;
                  for (auto& s : soak.counters().sessions) n += s;
                  return n;
                }(),
                static_cast<unsigned long long>(soak.counters().lockstep_frames.load()),
                static_cast<unsigned long long>(soak.counters().lost_lockstep.load()));
    std::fflush(stdout);
    if (!warmed && sample.seconds >= warmup) {
      warm = Checkpoint(soak, options, elapsed(), baseline_fds);
      warmed = true;
      std::printf("soak: warm-up checkpoint: rss %.1f MiB, fds %d\n", warm.rss / 1048576.0, warm.fds);
    }
  }
  if (!daemon_died) end = Checkpoint(soak, options, elapsed(), baseline_fds);
  soak.Stop();
  for (auto& worker : workers) worker.join();
  daemon_died = daemon_died || RssBytes(options.pid) == 0;

  Counters& c = soak.counters();
  std::size_t peak = baseline_rss;
  for (const Sample& s : samples) peak = std::max(peak, s.rss);
  const double growth = warm.rss ? 100.0 * (static_cast<double>(end.rss) - warm.rss) / warm.rss : 0;
  const int fd_growth = end.fds - std::min(warm.fds, baseline_fds);
  unsigned long long sessions = 0;
  std::printf("\nsoak: %.0f s, %d clients\n", elapsed(), options.clients);
  for (int k = 0; k < kKinds; ++k) {
    std::printf("  %-13s %llu sessions\n", kKindNames[k], static_cast<unsigned long long>(c.sessions[k].load()));
    sessions += c.sessions[k];
  }
  std::printf("  sessions completed %llu; refused by the daemon %llu; connection errors %llu; other errors %llu\n",
              sessions, static_cast<unsigned long long>(c.refused.load()),
              static_cast<unsigned long long>(c.connection_errors.load()),
              static_cast<unsigned long long>(c.other_errors.load()));
  std::printf("  frames: lockstep %llu, newest %llu; lost lockstep frames %llu (UDP frames waited for over 1 s and Stepped again: %llu)\n",
              static_cast<unsigned long long>(c.lockstep_frames.load()),
              static_cast<unsigned long long>(c.newest_frames.load()),
              static_cast<unsigned long long>(c.lost_lockstep.load()),
              static_cast<unsigned long long>(c.udp_incomplete.load()));
  std::printf("  rss: start %.1f MiB, after warm-up %.1f MiB, end %.1f MiB, peak %.1f MiB: growth %+.2f%%\n",
              baseline_rss / 1048576.0, warm.rss / 1048576.0, end.rss / 1048576.0, peak / 1048576.0, growth);
  std::printf("  fds: start %d, after warm-up %d, end %d: growth %d\n", baseline_fds, warm.fds, end.fds, fd_growth);
  if (daemon) {
    const auto warnings = daemon->warning_lines();
    std::printf("  daemon warnings: %zu%s%s\n", warnings.size(), warnings.empty() ? "" : "; first: ",
                warnings.empty() ? "" : warnings.front().c_str());
    if (daemon->Stop() != 0) daemon_died = true;
  }
  const bool ok = !daemon_died && warmed && growth <= 5.0 && fd_growth <= 0 && c.lost_lockstep == 0;
  std::printf("soak: %s (targets: RSS growth <= 5%% after warm-up, no fd growth, no lost lockstep frame%s)\n",
              ok ? "PASS" : "FAIL", daemon_died ? "; the daemon died" : "");
  return ok ? 0 : 1;
}
