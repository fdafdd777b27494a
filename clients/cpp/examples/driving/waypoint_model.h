// The driving case study's waypoint network (docs/driving.md, "ONNX
// contract") run by OpenCV's DNN: an ONNX file written by
// sim4cv.driving_net.export_onnx, checked against the contract when loaded.
//
//   input  image      [1, 3, H, W] float32  RGB (not BGR), 0 ... 255, CHW
//   input  goal       [1, 1]       float32  -1 left, 0 straight, +1 right (only with use_goal)
//   output waypoints  [1, 8]       float32  v1 h1 v2 h2 v3 h3 v4 h4, metres, h positive right
//
//   sim4cv::driving::WaypointModel model("model.onnx");   // 90x160 after driving_train
//   Waypoints w = model.Predict(rgb_8uc3, /*goal=*/0);      // any size: resized with INTER_AREA
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <stdexcept>
#include <string>

#include "driving/controller.h"

namespace sim4cv::driving {

// A model file that is missing, unreadable or breaks the contract; the
// message names the file and, for a shape, the expected and the found one.
class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class WaypointModel {
 public:
  static constexpr const char* kImageInput = "image";
  static constexpr const char* kGoalInput = "goal";
  static constexpr const char* kOutput = "waypoints";

  // Loads `path` with cv::dnn::readNetFromONNX. The image size is the one
  // the file declares for "image" (export_onnx writes fixed shapes); the
  // inputs and outputs are checked against the contract and a dry run must
  // give 8 numbers. Throws ModelError otherwise.
  explicit WaypointModel(const std::string& path);

  // The 8 outputs for one H x W x 3 uint8 RGB image (RGB, not BGR; any size:
  // resized to the model's with INTER_AREA if it differs). `goal` is fed to a
  // model with a "goal" input and ignored by one without (as
  // sim4cv.driving_net.load_onnx_with_opencv does). Throws
  // std::invalid_argument for an image that is not 8-bit 3-channel.
  Waypoints Predict(const cv::Mat& rgb, float goal = 0.0f);

  int width() const { return width_; }
  int height() const { return height_; }
  bool has_goal() const { return has_goal_; }
  const std::string& path() const { return path_; }

 private:
  Waypoints Run(const cv::Mat& rgb_at_model_size, float goal);

  std::string path_;
  cv::dnn::Net net_;
  int width_ = 0;
  int height_ = 0;
  bool has_goal_ = false;
  cv::Mat resized_;  // reused between frames
  cv::Mat goal_blob_;
};

}  // namespace sim4cv::driving
