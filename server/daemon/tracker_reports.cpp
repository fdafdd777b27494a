#include "server/daemon/tracker_reports.h"

#include <algorithm>

namespace sim4cv::daemon {

void RecordTrackerReport(sim::State& state, session::ClientId client, const session::TrackerOutputCommand& output) {
  const sim::TrackerReport report{client,         output.frame_id, output.x, output.y, output.width, output.height,
                                  output.confidence};
  auto& reports = state.tracker_reports;
  const auto it = std::lower_bound(reports.begin(), reports.end(), client,
                                   [](const sim::TrackerReport& r, session::ClientId id) { return r.client_id < id; });
  if (it != reports.end() && it->client_id == client) {
    *it = report;
  } else {
    reports.insert(it, report);
  }
}

void ForgetTrackerReport(sim::State& state, session::ClientId client) {
  std::erase_if(state.tracker_reports, [client](const sim::TrackerReport& r) { return r.client_id == client; });
}

}  // namespace sim4cv::daemon
