// The poses of a recorded run, indexed by frame id, for replay: the daemon
// makes each entity follow its logged pose and renders the cameras as they
// were (the paper replays "the trajectory of the vehicle ... from a log file
// to ensure equal conditions for all trackers"), and tools draw the paths.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "server/sim/log/run_log.h"
#include "server/sim/log/run_log_reader.h"

namespace sim4cv::runlog {

class ReplayTrack {
 public:
  // Reads every remaining record of `reader` (a damaged tail is dropped, as
  // the reader does; corruption in the middle throws).
  explicit ReplayTrack(RunLogReader& reader);
  // Opens `path` and reads all of it.
  static ReplayTrack Load(const std::string& path);

  const RunLogHeader& header() const { return header_; }
  std::size_t frame_count() const { return frames_.size(); }
  bool empty() const { return frames_.empty(); }
  // Frame ids in log order (increasing; gaps where frames were not logged).
  uint64_t frame_id(std::size_t index) const { return frames_[index].frame_id; }
  double sim_time(std::size_t index) const { return frames_[index].sim_time; }
  // Bytes of a damaged tail the reader dropped.
  uint64_t ignored_bytes() const { return ignored_bytes_; }

  // Index of the frame with this id, if it was logged.
  std::optional<std::size_t> IndexOf(uint64_t frame_id) const;
  // Every entity's logged state at a frame index, in the order it was logged.
  std::span<const EntityLog> EntitiesAt(std::size_t index) const;
  // The logged state of `entity_id` at frame `frame_id`, or nullptr if that
  // frame or that entity was not logged.
  const sim::BodyState* Find(uint64_t frame_id, uint32_t entity_id) const;

  // One entity's positions over the whole log, in frame order (frames that
  // do not hold it are skipped): what a 2D map of trajectories draws.
  std::vector<Eigen::Vector3d> PositionsOf(uint32_t entity_id) const;

 private:
  struct FrameSpan {
    uint64_t frame_id = 0;
    double sim_time = 0.0;
    std::size_t first = 0, count = 0;  // into entities_
  };
  RunLogHeader header_;
  std::vector<FrameSpan> frames_;
  std::vector<EntityLog> entities_;  // all frames' entities, back to back
  uint64_t ignored_bytes_ = 0;
};

}  // namespace sim4cv::runlog
