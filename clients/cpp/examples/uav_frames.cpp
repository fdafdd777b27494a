// sim4cv_uav_frames: subscribes to the "uav" camera, receives frames with
// ground truth, reports per-frame latency (render end -> frame in hand) and
// saves a few annotated PNGs.
//
//   sim4cv_uav_frames --address shm:///sim4cv | udp://127.0.0.1:40124 [--frames 100] [--out DIR] [--save 5]
//   sim4cv_uav_frames --port 40123 [--host 127.0.0.1] ...   (the same as --address tcp://HOST:PORT)
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "channel_colours.h"
#include "flags.h"
#include "sim4cv/client.h"

namespace {

using sim4cv::proto::Frame;

struct Options {
  std::string address;  // tcp://, udp:// or shm://; empty: tcp://host:port
  std::string host = "127.0.0.1";
  int port = 0;
  int frames = 100;
  std::string out = "sim4cv_frames";
  int save = 5;
};

using sim4cv::examples::ParseNumber;
using sim4cv::examples::UsageError;

Options ParseArgs(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") throw UsageError("");
    if (i + 1 >= argc) throw UsageError("missing value after " + flag);
    const std::string value = argv[++i];
    if (flag == "--address") {
      options.address = value;
    } else if (flag == "--host") {
      options.host = value;
    } else if (flag == "--port") {
      options.port = ParseNumber(flag, value, 1, 65535);
    } else if (flag == "--frames") {
      options.frames = ParseNumber(flag, value, 1, 100000000);
    } else if (flag == "--out") {
      options.out = value;
    } else if (flag == "--save") {
      options.save = ParseNumber(flag, value, 0, 100000000);
    } else {
      throw UsageError("unknown flag: " + flag);
    }
  }
  if (options.address.empty()) {
    if (options.port == 0) throw UsageError("--address or --port is required");
    options.address = "tcp://" + options.host + ":" + std::to_string(options.port);
  }
  return options;
}

int64_t MonotonicNs() {
  // The daemon stamps render_end_mono_ns with CLOCK_MONOTONIC; steady_clock
  // is not guaranteed to be the same clock.
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

void PrintWelcome(const sim4cv::proto::Welcome& welcome) {
  std::printf("connected: sim4cvd %s, scene '%s', %s mode, physics %.0f Hz, frames %.0f Hz, client id %u\n",
              welcome.server_version().c_str(), welcome.scene_name().c_str(),
              sim4cv::proto::SimMode_Name(welcome.mode()).c_str(), welcome.physics_hz(), welcome.frame_hz(),
              welcome.client_id());
  for (const auto& camera : welcome.cameras()) {
    std::printf("  camera '%s' %ux%u fov_y %.1f deg%s%s\n", camera.name().c_str(), camera.width(), camera.height(),
                camera.fov_y_deg(), camera.mounted_on().empty() ? "" : " on ", camera.mounted_on().c_str());
  }
  for (const auto& entity : welcome.entities()) {
    std::printf("  entity %u '%s' %s\n", entity.id(), entity.name().c_str(),
                sim4cv::proto::EntityKind_Name(entity.kind()).c_str());
  }
}

// `count` indices spread over [0, total), first and last included.
std::vector<int> EvenlySpaced(int count, int total) {
  count = std::min(count, total);
  std::vector<int> indices;
  for (int i = 0; i < count; ++i) {
    indices.push_back(count == 1 ? 0 : static_cast<int>(static_cast<int64_t>(i) * (total - 1) / (count - 1)));
  }
  return indices;
}

// A cv::Mat over the channel's pixels (no copy); empty if the frame lacks it.
cv::Mat Wrap(const Frame& frame, sim4cv::proto::Channel channel, int cv_type) {
  const auto view = sim4cv::FindImage(frame, channel);
  if (!view) return {};
  return cv::Mat(static_cast<int>(view->height), static_cast<int>(view->width), cv_type,
                 const_cast<uint8_t*>(view->data), view->stride);
}

cv::Mat AnnotatedRgb(const Frame& frame) {
  cv::Mat bgr;
  cv::cvtColor(Wrap(frame, sim4cv::proto::CHANNEL_RGB, CV_8UC3), bgr, cv::COLOR_RGB2BGR);
  const cv::Scalar green(0, 255, 0);
  for (const auto& box : frame.boxes()) {
    const cv::Rect rect(static_cast<int>(box.x()), static_cast<int>(box.y()), static_cast<int>(box.width()),
                        static_cast<int>(box.height()));
    cv::rectangle(bgr, rect, green, 1);
    char label[48];
    std::snprintf(label, sizeof label, "#%u %.2f", box.object_id(), box.visibility());
    const cv::Point origin(rect.x, std::max(rect.y - 2, 8));
    cv::putText(bgr, label, origin, cv::FONT_HERSHEY_PLAIN, 0.7, green, 1);
  }
  return bgr;
}

void Write(const std::filesystem::path& path, const cv::Mat& image) {
  if (!cv::imwrite(path.string(), image)) throw std::runtime_error("cannot write " + path.string());
  std::printf("wrote %s\n", path.c_str());
}

void SaveFrames(const std::vector<Frame>& frames, const std::string& out_dir) {
  if (frames.empty()) return;
  std::filesystem::create_directories(out_dir);
  const auto name = [&](const char* what, const Frame& frame) {
    char file[64];
    std::snprintf(file, sizeof file, "%s_%06llu.png", what, static_cast<unsigned long long>(frame.frame_id()));
    return std::filesystem::path(out_dir) / file;
  };
  for (const Frame& frame : frames) Write(name("frame", frame), AnnotatedRgb(frame));
  // The ground truth of the last saved frame (the first has no motion for flow).
  using namespace sim4cv::examples;
  const Frame& last = frames.back();
  const struct {
    const char* what;
    sim4cv::proto::Channel channel;
    int cv_type;
    cv::Mat (*colours)(const cv::Mat&);
  } truths[] = {{"depth", sim4cv::proto::CHANNEL_DEPTH, CV_32FC1, DepthColours},
                {"mask", sim4cv::proto::CHANNEL_MASK, CV_16UC1, MaskColours},
                {"semantic", sim4cv::proto::CHANNEL_SEMANTIC, CV_8UC1, SemanticColours},
                {"normals", sim4cv::proto::CHANNEL_NORMALS, CV_32FC3, NormalsColours},
                {"flow", sim4cv::proto::CHANNEL_FLOW, CV_32FC2, FlowColours}};
  for (const auto& truth : truths) {
    const cv::Mat pixels = Wrap(last, truth.channel, truth.cv_type);
    if (!pixels.empty()) Write(name(truth.what, last), truth.colours(pixels));
  }
}

double Percentile(std::vector<double> sorted_copy, double fraction) {
  std::sort(sorted_copy.begin(), sorted_copy.end());
  const auto rank = static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(sorted_copy.size())));
  return sorted_copy[std::clamp<std::size_t>(rank, 1, sorted_copy.size()) - 1];
}

int Run(const Options& options) {
  sim4cv::Client client;
  client.Connect(options.address, "sim4cv_uav_frames");
  PrintWelcome(client.welcome());

  // A realtime daemon refuses lockstep delivery and advances on its own.
  const bool lockstep = client.welcome().mode() != sim4cv::proto::SIM_MODE_REALTIME;
  client.Subscribe("uav",
                   {sim4cv::proto::CHANNEL_RGB, sim4cv::proto::CHANNEL_DEPTH, sim4cv::proto::CHANNEL_MASK,
                    sim4cv::proto::CHANNEL_BOXES, sim4cv::proto::CHANNEL_SEMANTIC, sim4cv::proto::CHANNEL_NORMALS,
                    sim4cv::proto::CHANNEL_FLOW},
                   lockstep ? sim4cv::proto::DELIVERY_LOCKSTEP : sim4cv::proto::DELIVERY_NEWEST);

  const std::vector<int> save_at = EvenlySpaced(options.save, options.frames);
  std::vector<Frame> to_save;
  std::vector<double> latencies_us;
  latencies_us.reserve(static_cast<std::size_t>(options.frames));
  Frame frame;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < options.frames; ++i) {
    if (lockstep) client.Step();
    if (!client.ReceiveFrame(frame)) {
      throw sim4cv::ConnectionError("timed out waiting for frame " + std::to_string(i + 1));
    }
    // Measured before anything else touches the frame.
    const double latency_us = static_cast<double>(MonotonicNs() - frame.render_end_mono_ns()) / 1000.0;
    latencies_us.push_back(latency_us);
    std::printf("frame %llu  t=%.3f s  boxes=%d  latency=%.0f us\n", static_cast<unsigned long long>(frame.frame_id()),
                frame.sim_time(), frame.boxes_size(), latency_us);
    if (std::find(save_at.begin(), save_at.end(), i) != save_at.end()) to_save.push_back(frame);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::printf("%d frames in %.3f s: %.1f fps; latency median %.0f us, p99 %.0f us, max %.0f us", options.frames,
              seconds, options.frames / seconds, Percentile(latencies_us, 0.5), Percentile(latencies_us, 0.99),
              *std::max_element(latencies_us.begin(), latencies_us.end()));
  if (!lockstep) std::printf(", %llu dropped", static_cast<unsigned long long>(frame.dropped_frames()));
  std::printf("\n");
  SaveFrames(to_save, options.out);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(ParseArgs(argc, argv));
  } catch (const UsageError& e) {
    if (*e.what() != '\0') std::cerr << "sim4cv_uav_frames: " << e.what() << "\n";
    std::cerr
        << "usage: sim4cv_uav_frames (--address tcp://H:P|udp://H:P|shm://NAME | --port P [--host H]) [--frames N] "
           "[--out DIR] [--save K]\n";
    return 2;
  } catch (const sim4cv::ServerError& e) {
    std::cerr << "sim4cv_uav_frames: sim4cvd refused: " << sim4cv::proto::ErrorCode_Name(e.code()) << ": " << e.what()
              << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "sim4cv_uav_frames: " << e.what() << "\n";
    return 1;
  }
}
