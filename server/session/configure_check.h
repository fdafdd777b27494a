// Checks a Configure's fields on their own (the network thread): every
// number finite and in its documented range, a request present, names and
// map texts within bounds. What needs the world (ids, names, the map's
// lines) is checked by the sim thread when it carries the request out.
#pragma once

#include <string>

#include "sim4cv.pb.h"

namespace sim4cv::session {

// Empty if `request` may go to the sim thread; otherwise what is wrong,
// naming the field and its value.
std::string CheckConfigure(const proto::Configure& request);

}  // namespace sim4cv::session
