// What a run log holds (docs/logs.md): a header describing the run, then one
// record per simulated frame with the pose of every entity, the boxes the
// trackers reported, the ground-truth boxes and the car controls. The paper
// logs "at each frame ... the current bounding box, position, orientation,
// and velocity of the tracked target and the UAV"; these logs are what its
// replay and its 2D map of tracker trajectories are made from.
//
// Poses and car commands reuse the simulation's own structs (state.h), so the
// sim thread copies State into a record and replay copies them back.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "server/sim/state.h"

namespace sim4cv::runlog {

// Bytes 0..7 of every run log.
inline constexpr char kMagic[8] = {'S', '4', 'C', 'V', 'L', 'O', 'G', '\0'};
// Layout of the file: magic, version, framing, header fields.
inline constexpr uint32_t kFormatVersion = 1;
// Layout of a frame record's payload, stored in the header.
inline constexpr uint32_t kRecordVersion = 1;
// Records (and the header) larger than this are refused by the writer and
// taken for damage by the reader: a frame of ~100 entities is ~15 KB.
inline constexpr uint32_t kMaxRecordBytes = 64u << 20;

// Values of the protocol's EntityKind and ObjectClass (protocol/sim4cv.proto),
// repeated here so the library needs no protobuf; a test checks they agree.
inline constexpr uint16_t kEntityKindCar = 1;
inline constexpr uint16_t kEntityKindUav = 2;
inline constexpr uint16_t kEntityKindPedestrian = 3;
inline constexpr uint16_t kObjectClassCar = 1;
inline constexpr uint16_t kObjectClassUav = 2;
inline constexpr uint16_t kObjectClassPedestrian = 7;

// A tracker box whose camera the daemon did not know.
inline constexpr uint16_t kNoCamera = 0xFFFF;

struct LogEntity {
  uint32_t id = 0;  // EntityInfo.id, also the instance id in masks and boxes
  std::string name;
  uint16_t kind = 0;          // proto EntityKind value
  uint16_t object_class = 0;  // proto ObjectClass value
  friend bool operator==(const LogEntity&, const LogEntity&) = default;
};

struct LogCamera {
  std::string name;
  uint32_t mounted_on = 0;  // entity id, 0 if fixed in the world
  uint32_t width = 0, height = 0;
  friend bool operator==(const LogCamera&, const LogCamera&) = default;
};

struct RunLogHeader {
  // Set by the writer (kRecordVersion); the reader reports what the file says.
  uint32_t record_version = kRecordVersion;
  // Creation info. The writer puts the current time here when it is 0.
  int64_t created_unix_ns = 0;
  std::string creator;  // e.g. "sim4cvd 0.1.0"
  // What this run is, e.g. the tracker driving the UAV; drawings name it.
  std::string label;
  std::string scene_name;  // Scene::name or Map::name
  std::string map_path;    // file the map was loaded from, if any
  double physics_hz = 0.0;
  double frame_hz = 0.0;
  uint64_t seed = 0;
  // How the images looked, e.g. "rain at 15.00 h, full quality"
  // (protocol/conditions.h Describe); empty in logs written before it existed.
  std::string conditions;
  std::vector<LogEntity> entities;
  std::vector<LogCamera> cameras;  // GroundTruthBoxLog::camera indexes this

  const LogEntity* FindEntity(uint32_t id) const;
  const LogEntity* FindEntity(const std::string& name) const;
  friend bool operator==(const RunLogHeader&, const RunLogHeader&) = default;
};

struct EntityLog {
  uint32_t id = 0;
  sim::BodyState body;  // position, orientation (body -> world), world-frame velocities
};

struct TrackerBoxLog {
  uint16_t camera = kNoCamera;  // index into RunLogHeader::cameras
  sim::TrackerReport box;       // client id, the frame it refers to, x y w h, confidence
};

// The ground-truth box of an object as one camera saw it this frame.
struct GroundTruthBoxLog {
  uint16_t camera = 0;  // index into RunLogHeader::cameras
  uint32_t object_id = 0;
  uint32_t x = 0, y = 0, width = 0, height = 0;  // pixels; x + width is one past the right-most column
  float visibility = 0.0f;                       // visible / unoccluded pixels, (0, 1]
};

struct CarControlLog {
  uint32_t entity_id = 0;
  sim::CarCommand command;  // steering, throttle, brake, manual
};

struct FrameLogRecord {
  uint64_t frame_id = 0;  // strictly increasing within a log
  double sim_time = 0.0;  // seconds
  std::vector<EntityLog> entities;
  std::vector<TrackerBoxLog> tracker_boxes;
  std::vector<GroundTruthBoxLog> ground_truth;
  std::vector<CarControlLog> controls;

  // Empties the lists but keeps their capacity, so a record reused every
  // frame stops allocating once it has seen the largest frame.
  void Clear();
};

}  // namespace sim4cv::runlog
