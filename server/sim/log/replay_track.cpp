#include "server/sim/log/replay_track.h"

#include <algorithm>

namespace sim4cv::runlog {

ReplayTrack::ReplayTrack(RunLogReader& reader) : header_(reader.header()) {
  FrameLogRecord record;
  while (reader.Next(&record)) {
    frames_.push_back({record.frame_id, record.sim_time, entities_.size(), record.entities.size()});
    entities_.insert(entities_.end(), record.entities.begin(), record.entities.end());
  }
  ignored_bytes_ = reader.ignored_bytes();
}

ReplayTrack ReplayTrack::Load(const std::string& path) {
  RunLogReader reader(path);
  return ReplayTrack(reader);
}

std::optional<std::size_t> ReplayTrack::IndexOf(uint64_t frame_id) const {
  // The reader guarantees increasing frame ids, so a binary search finds it.
  const auto it = std::lower_bound(frames_.begin(), frames_.end(), frame_id,
                                   [](const FrameSpan& frame, uint64_t id) { return frame.frame_id < id; });
  if (it == frames_.end() || it->frame_id != frame_id) return std::nullopt;
  return static_cast<std::size_t>(it - frames_.begin());
}

std::span<const EntityLog> ReplayTrack::EntitiesAt(std::size_t index) const {
  const FrameSpan& frame = frames_.at(index);
  return std::span<const EntityLog>(entities_).subspan(frame.first, frame.count);
}

const sim::BodyState* ReplayTrack::Find(uint64_t frame_id, uint32_t entity_id) const {
  const std::optional<std::size_t> index = IndexOf(frame_id);
  if (!index) return nullptr;
  for (const EntityLog& entity : EntitiesAt(*index)) {
    if (entity.id == entity_id) return &entity.body;
  }
  return nullptr;
}

std::vector<Eigen::Vector3d> ReplayTrack::PositionsOf(uint32_t entity_id) const {
  std::vector<Eigen::Vector3d> positions;
  for (const EntityLog& entity : entities_) {
    if (entity.id == entity_id) positions.push_back(entity.body.position);
  }
  return positions;
}

}  // namespace sim4cv::runlog
