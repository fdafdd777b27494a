#include "server/daemon/tracker_reports.h"

#include <algorithm>
#include <sstream>

namespace sim4cv::daemon {
namespace {

// A box that misses the image grown by one image size on every side is no
// tracker's estimate of anything in it.
bool FarOutside(const session::TrackerOutputCommand& box, const ReportCamera& camera) {
  const double w = camera.width, h = camera.height;
  return box.x > 2 * w || box.y > 2 * h || box.x + box.width < -w || box.y + box.height < -h;
}

}  // namespace

std::string RecordTrackerReport(sim::State& state, session::ClientId client,
                                const session::TrackerOutputCommand& output, const ReportCamera* camera) {
  std::ostringstream problem;
  problem << "TrackerOutput for frame " << output.frame_id << " ignored: ";
  if (!camera) {
    problem << "this client subscribes to no camera, so the box is in no image; Subscribe first";
    return problem.str();
  }
  if (output.frame_id == 0 || output.frame_id > state.frame_id) {
    problem << "frame " << output.frame_id << " was never rendered (the newest is " << state.frame_id
            << "); answer with the frame_id of the frame the box is in";
    return problem.str();
  }
  auto& reports = state.tracker_reports;
  const auto it = std::lower_bound(reports.begin(), reports.end(), client,
                                   [](const sim::TrackerReport& r, session::ClientId id) { return r.client_id < id; });
  const bool known = it != reports.end() && it->client_id == client;
  if (known && output.frame_id <= it->frame_id) {
    problem << "this client already reported frame " << it->frame_id << "; answer each frame at most once, in order";
    return problem.str();
  }
  if (FarOutside(output, *camera)) {
    problem << "the box (x " << output.x << ", y " << output.y << ", " << output.width << " x " << output.height
            << ") lies far outside the " << camera->width << "x" << camera->height << " image of camera '"
            << camera->name << "'";
    return problem.str();
  }
  const sim::TrackerReport report{client,        output.frame_id, output.x,          output.y,
                                  output.width,  output.height,   output.confidence, camera->entity_id,
                                  camera->width, camera->height,  state.sim_time};
  if (known) {
    *it = report;
  } else {
    reports.insert(it, report);
  }
  return "";
}

void ForgetTrackerReport(sim::State& state, session::ClientId client) {
  std::erase_if(state.tracker_reports, [client](const sim::TrackerReport& r) { return r.client_id == client; });
}

}  // namespace sim4cv::daemon
