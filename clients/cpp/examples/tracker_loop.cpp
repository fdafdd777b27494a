// A complete tracker in the loop over any transport (docs/clients.md): an
// OpenCV KCF tracker, initialised with the car's ground-truth box (object 1),
// answers every lockstep frame with its box.
//   sim4cv_tracker_loop shm:///sim4cv [frames]
#include <opencv2/tracking.hpp>

#include "sim4cv/client.h"

int main(int argc, char** argv) {
  using namespace sim4cv;
  Client client;
  client.Connect(argc > 1 ? argv[1] : "shm:///sim4cv", "kcf-tracker");
  client.Subscribe("uav", {proto::CHANNEL_RGB, proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  cv::Ptr<cv::Tracker> tracker;
  for (int i = 0; i < (argc > 2 ? std::atoi(argv[2]) : 300); ++i) {
    const proto::Frame& frame = client.StepAndReceive();
    const ImageView rgb = *FindImage(frame, proto::CHANNEL_RGB);
    const cv::Mat image(rgb.height, rgb.width, CV_8UC3, const_cast<uint8_t*>(rgb.data), rgb.stride);
    cv::Rect box;
    if (!tracker) {
      const proto::Box& car = frame.boxes(0);  // ordered by object id: the car (1) first
      box = cv::Rect(car.x(), car.y(), car.width(), car.height());
      (tracker = cv::TrackerKCF::create())->init(image, box);
    } else if (!tracker->update(image, box)) {
      box = {};
    }
    client.SendTrackerOutput(frame.frame_id(), box.x, box.y, box.width, box.height, box.area() > 0 ? 1.f : 0.f);
  }
  std::printf("tracked %d frames over %s\n", argc > 2 ? std::atoi(argv[2]) : 300, client.address().c_str());
}
