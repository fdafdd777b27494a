// Colour images of the ground-truth channels, for saving as PNGs (OpenCV,
// BGR): depth false-coloured, instance ids, semantic classes in the
// Cityscapes palette, normals, and optical flow on the usual colour wheel.
#pragma once

#include <opencv2/core.hpp>

namespace sim4cv::examples {

// float32 metres -> near warm, far cool; +inf (sky) black.
cv::Mat DepthColours(const cv::Mat& depth);
// uint16 instance ids -> a fixed colour per id; 0 black.
cv::Mat MaskColours(const cv::Mat& mask);
// uint8 class ids -> the palette of protocol/semantic_classes.h.
cv::Mat SemanticColours(const cv::Mat& semantic);
// 3 x float32 unit normals -> (n + 1) / 2 as RGB; sky (0,0,0) black.
cv::Mat NormalsColours(const cv::Mat& normals);
// 2 x float32 pixels -> hue = direction, saturation = magnitude / the
// largest finite magnitude; NaN black.
cv::Mat FlowColours(const cv::Mat& flow);

}  // namespace sim4cv::examples
