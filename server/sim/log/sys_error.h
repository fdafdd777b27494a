// The one way the run-log code reports a failed system call: a
// std::system_error reading "run log PATH: WHAT: ERRNO TEXT".
#pragma once

#include <string>
#include <system_error>

namespace sim4cv::runlog::detail {

[[noreturn]] inline void ThrowErrno(int error, const std::string& path, const char* what) {
  throw std::system_error(error, std::generic_category(), "run log " + path + ": " + what);
}

}  // namespace sim4cv::runlog::detail
