// A rendered frame of one camera, built once by the sim thread and then
// shared read-only by every transport that delivers it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "server/render/ground_truth.h"
#include "server/render/object_catalog.h"
#include "server/render/projection.h"
#include "server/session/ref_pool.h"
#include "sim4cv.pb.h"

namespace sim4cv::session {

struct Frame {
  uint64_t frame_id = 0;
  double sim_time = 0.0;
  uint32_t camera_index = 0;
  // The camera's name as the frame was rendered, so transports need not look
  // it up in a camera list that may change meanwhile. A pooled frame keeps the
  // string's capacity, so assigning a name no longer than before allocates nothing.
  std::string camera_name;
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> rgb;     // width*height*3
  std::vector<float> depth;     // width*height, metres
  std::vector<uint16_t> mask;   // width*height instance ids
  std::vector<render::GroundTruthBox> boxes;
  render::CameraIntrinsics intrinsics;
  render::Pose camera_pose;  // OpenCV axes (x right, y down, z forward) -> world
  std::vector<render::ObjectGroundTruth> objects;  // ordered by instance id (ObjectCatalog::Fill)
  int64_t render_end_mono_ns = 0;
  proto::State state;  // entity poses at this frame (reused message)
};

using FramePool = RefPool<Frame>;
using FrameRef = PoolRef<Frame>;

// The State snapshot every GetState is answered from, published each frame.
struct StateSnapshot {
  proto::State state;  // without last_tracker_output
  std::vector<proto::TrackerOutput> tracker_outputs;  // parallel to tracker_clients
  std::vector<uint32_t> tracker_clients;
};

using StatePool = RefPool<StateSnapshot>;
using StateRef = PoolRef<StateSnapshot>;

}  // namespace sim4cv::session
