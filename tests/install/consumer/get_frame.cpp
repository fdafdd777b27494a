// A user's program outside the source tree: one frame from a running sim4cvd through the
// installed client library. Built by tests/install/test_install.sh twice, with
// find_package(sim4cv) (CMakeLists.txt here) and with pkg-config.
//   get_frame ADDRESS        e.g. tcp://127.0.0.1:5555 or shm:///sim4cv
// Prints "frame ID WIDTHxHEIGHT rgb_mean M" and exits 0; on any error prints it, exits 1.
#include <cstdio>
#include <exception>

#include <sim4cv/client.h>
#include <sim4cv/shm_client.h>  // compiles only if the installed protocol headers are self-contained

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: get_frame ADDRESS\n");
    return 2;
  }
  try {
    sim4cv::Client client;
    client.Connect(argv[1], "install-test");
    client.Subscribe("uav", {sim4cv::proto::CHANNEL_RGB}, sim4cv::proto::DELIVERY_LOCKSTEP);
    const sim4cv::proto::Frame& frame = client.StepAndReceive();
    const auto rgb = sim4cv::FindImage(frame, sim4cv::proto::CHANNEL_RGB);
    if (!rgb || rgb->width == 0 || rgb->height == 0) {
      std::fprintf(stderr, "get_frame: frame %llu has no RGB image\n", static_cast<unsigned long long>(frame.frame_id()));
      return 1;
    }
    double sum = 0;
    for (uint32_t y = 0; y < rgb->height; ++y)
      for (uint32_t x = 0; x < rgb->width; ++x) sum += *rgb->at<uint8_t>(x, y);
    std::printf("frame %llu %ux%u rgb_mean %.1f\n", static_cast<unsigned long long>(frame.frame_id()), rgb->width,
                rgb->height, sum / (static_cast<double>(rgb->width) * rgb->height));
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "get_frame: %s\n", error.what());
    return 1;
  }
}
