// Conversions from sim4cv protobuf messages to Octave/MATLAB values for the
// MEX gateway sim4cv_mex.cpp. Pixels arrive as rows top to bottom (C order,
// docs/protocol.md section 8); MATLAB arrays are column-major, so each
// channel is transposed into an H x W x C array in one pass.
#pragma once

#include <string>

#include "mex.h"
#include "sim4cv/client.h"

namespace sim4cv::mexbind {

// A struct with frame_id, sim_time, camera, render_end_mono_ns (int64),
// width, height, dropped_frames, one field per pixel channel (rgb uint8
// HxWx3, depth single HxW, mask uint16 HxW, semantic uint8, normals single
// HxWx3, flow single HxWx2), boxes (Nx1 struct array, 0x1 if none) and
// intrinsics ([] unless CHANNEL_BOXES was subscribed). Throws
// ConnectionError if an image is shorter than its size says.
mxArray* FrameToStruct(const proto::Frame& frame);

// A struct with frame_id, sim_time and entities (Nx1 struct array: id, name,
// kind, position [x y z], yaw (degrees counter-clockwise from east),
// orientation [w x y z], velocity [vx vy vz]) and last_tracker_output
// (frame_id, box [x y w h], confidence).
mxArray* StateToStruct(const proto::State& state);

// A struct with scene_name, frame_id, entities (Nx1 struct: id, name, kind),
// cameras (Nx1 struct: name, width, height, fov_y_deg, mounted_on) and
// routes (cellstr).
mxArray* WorldToStruct(const proto::WorldInfo& world);

// "car" for ENTITY_KIND_CAR, "uav", "pedestrian"; lower-case enum names
// without their prefix (object classes too: "building", "tree", ...).
std::string KindName(proto::EntityKind kind);
std::string ClassName(proto::ObjectClass object_class);

}  // namespace sim4cv::mexbind
