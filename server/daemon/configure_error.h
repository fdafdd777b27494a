// The one exception a Configure's handlers throw: it becomes the Error the
// client reads (docs/protocol.md, "Errors"), so its message says what was
// wrong and what to do instead.
#pragma once

#include <stdexcept>
#include <string>

#include "sim4cv.pb.h"

namespace sim4cv::daemon {

// A Configure that cannot be carried out: the code and message of its Error.
class ConfigureError : public std::runtime_error {
 public:
  ConfigureError(proto::ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  proto::ErrorCode code() const { return code_; }

 private:
  proto::ErrorCode code_;
};

}  // namespace sim4cv::daemon
