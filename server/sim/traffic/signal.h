// A traffic light's signal. Header-only, so a renderer can name the lit lamp
// without linking the traffic library.
#pragma once

#include <cstdint>

namespace sim4cv::traffic {

enum class Signal : uint8_t { kGreen, kYellow, kRed };

constexpr const char* SignalName(Signal signal) {
  switch (signal) {
    case Signal::kGreen:
      return "green";
    case Signal::kYellow:
      return "yellow";
    case Signal::kRed:
      return "red";
  }
  return "?";
}

}  // namespace sim4cv::traffic
