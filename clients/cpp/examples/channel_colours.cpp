#include "channel_colours.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "protocol/semantic_classes.h"

namespace sim4cv::examples {

cv::Mat DepthColours(const cv::Mat& depth) {
  const cv::Mat finite = (depth == depth) & (depth < std::numeric_limits<float>::infinity());  // NaN != NaN
  double near = 0, far = 1;
  if (cv::countNonZero(finite) > 0) cv::minMaxLoc(depth, &near, &far, nullptr, nullptr, finite);
  cv::Mat scaled;
  depth.convertTo(scaled, CV_8U, -255.0 / std::max(far - near, 1e-6), 255.0 * far / std::max(far - near, 1e-6));
  cv::Mat coloured;
  cv::applyColorMap(scaled, coloured, cv::COLORMAP_TURBO);
  coloured.setTo(cv::Scalar::all(0), ~finite);
  return coloured;
}

cv::Mat MaskColours(const cv::Mat& mask) {
  cv::Mat coloured(mask.size(), CV_8UC3);
  for (int row = 0; row < mask.rows; ++row) {
    for (int col = 0; col < mask.cols; ++col) {
      const uint32_t id = mask.at<uint16_t>(row, col);
      coloured.at<cv::Vec3b>(row, col) =
          id == 0 ? cv::Vec3b(0, 0, 0) : cv::Vec3b(64 + id * 97 % 192, 64 + id * 57 % 192, 64 + id * 151 % 192);
    }
  }
  return coloured;
}

cv::Mat SemanticColours(const cv::Mat& semantic) {
  cv::Mat lut(1, 256, CV_8UC3, cv::Scalar::all(0));
  for (const semantic::SemanticClassInfo& info : semantic::kSemanticClasses) {
    lut.at<cv::Vec3b>(0, static_cast<int>(info.id)) = cv::Vec3b(info.colour[2], info.colour[1], info.colour[0]);
  }
  cv::Mat ids3, coloured;
  cv::cvtColor(semantic, ids3, cv::COLOR_GRAY2BGR);
  cv::LUT(ids3, lut, coloured);
  return coloured;
}

cv::Mat NormalsColours(const cv::Mat& normals) {
  cv::Mat rgb;
  normals.convertTo(rgb, CV_8UC3, 127.5, 127.5);
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  cv::Mat sky;
  cv::inRange(normals, cv::Scalar::all(0), cv::Scalar::all(0), sky);
  bgr.setTo(cv::Scalar::all(0), sky);
  return bgr;
}

cv::Mat FlowColours(const cv::Mat& flow) {
  std::vector<cv::Mat> parts;
  cv::split(flow, parts);
  const cv::Mat valid = (parts[0] == parts[0]) & (parts[1] == parts[1]);
  parts[0].setTo(0, ~valid);
  parts[1].setTo(0, ~valid);
  cv::Mat magnitude, angle;
  cv::cartToPolar(parts[0], parts[1], magnitude, angle, /*angleInDegrees=*/true);
  double largest = 0;
  cv::minMaxLoc(magnitude, nullptr, &largest);
  cv::Mat hsv[3];
  angle.convertTo(hsv[0], CV_8U, 0.5);  // OpenCV's 8-bit hue is degrees / 2
  magnitude.convertTo(hsv[1], CV_8U, 255.0 / std::max(largest, 1e-6));
  hsv[2] = cv::Mat(flow.size(), CV_8U, cv::Scalar(255));
  cv::Mat merged, bgr;
  cv::merge(hsv, 3, merged);
  cv::cvtColor(merged, bgr, cv::COLOR_HSV2BGR);
  bgr.setTo(cv::Scalar::all(0), ~valid);
  return bgr;
}

}  // namespace sim4cv::examples
