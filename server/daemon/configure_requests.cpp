#include "server/daemon/configure_request.h"

#include <array>

namespace sim4cv::daemon {

// The Configure requests that have a file of their own: one line each, the
// name of the ConfigureRequest that server/daemon/configure/NAME.cpp
// defines in namespace configure.
#define SIM4CV_CONFIGURE_REQUESTS(X) \
  X(kGetWorld)

namespace configure {
#define SIM4CV_DECLARE_REQUEST(NAME) extern const ConfigureRequest NAME;
SIM4CV_CONFIGURE_REQUESTS(SIM4CV_DECLARE_REQUEST)
#undef SIM4CV_DECLARE_REQUEST
}  // namespace configure

namespace {
#define SIM4CV_REQUEST_ADDRESS(NAME) &configure::NAME,
const std::array kConfigureRequests = {SIM4CV_CONFIGURE_REQUESTS(SIM4CV_REQUEST_ADDRESS)};
#undef SIM4CV_REQUEST_ADDRESS
}  // namespace

const ConfigureRequest* FindConfigureRequest(proto::Configure::RequestCase request_case) {
  for (const ConfigureRequest* request : kConfigureRequests) {
    if (request->request_case == request_case) return request;
  }
  return nullptr;
}

}  // namespace sim4cv::daemon
