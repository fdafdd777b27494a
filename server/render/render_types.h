// Plain data the renderer consumes and produces. No GL types leak out of here.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "protocol/channels.h"
#include "protocol/effects.h"
#include "protocol/semantic_classes.h"

namespace sim4cv::render {

using semantic::SemanticClass;

struct Vertex {
  float position[3];
  float normal[3];
  float color[3];  // linear RGB in [0, 1]
  // Bits 0-7: the SemanticClass (semantic_classes.h) of the surface, for
  // CHANNEL_SEMANTIC; kEmissive: the surface glows with its own colour when
  // the look's night lights are on (lamps, headlights).
  uint32_t semantic;
};

inline constexpr uint32_t kSemanticBits = 0xFF;
inline constexpr uint32_t kEmissive = 0x100;


// Indexed triangle list; front faces wind counter-clockwise seen from outside.
struct Mesh {
  std::vector<Vertex> vertices;
  std::vector<uint32_t> indices;
  // The semantic class the builders give vertices they append from now on
  // (semantic_classes.h; 255 unlabelled): a builder of a mixed surface (a
  // road with its markings) sets it before each part.
  uint32_t semantic = 255;
};

// Gives every vertex of `mesh` the class `semantic`, and makes it the class
// of vertices appended later; returns the mesh, for use on a fresh one.
inline Mesh Labelled(Mesh mesh, semantic::SemanticClass semantic) {
  for (Vertex& vertex : mesh.vertices) {
    vertex.semantic = (vertex.semantic & ~kSemanticBits) | static_cast<uint32_t>(semantic);  // keeps kEmissive
  }
  mesh.semantic = static_cast<uint32_t>(semantic);
  return mesh;
}

// Sets kEmissive on the vertices of `mesh` from `first` on (a part just appended).
inline void MarkEmissive(Mesh& mesh, std::size_t first) {
  for (std::size_t i = first; i < mesh.vertices.size(); ++i) mesh.vertices[i].semantic |= kEmissive;
}

// A car's headlights as one spot light: where it shines from and where to
// (world, unit), for the look's night lights.
struct Headlight {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();
  Eigen::Vector3f direction = Eigen::Vector3f::UnitX();
};

// Index into the mesh list the Renderer was built with.
using MeshId = uint32_t;
// DrawItem::far_mesh when the item has no lighter mesh.
inline constexpr MeshId kNoFarMesh = UINT32_MAX;

// Instance id 0 marks unlabelled geometry (ground, road); labelled objects use
// 1..65535 and show up in the mask and the boxes.
using InstanceId = uint16_t;
inline constexpr InstanceId kUnlabelled = 0;

struct DrawItem {
  MeshId mesh = 0;
  Eigen::Matrix4f world_from_model = Eigen::Matrix4f::Identity();
  InstanceId instance = kUnlabelled;
  // The same item's transform one frame earlier (for optical flow); equal to
  // world_from_model for what does not move or did not exist.
  Eigen::Matrix4f previous_world_from_model = Eigen::Matrix4f::Identity();
  // Never moves while the scene lasts (map objects, buildings): its shadow may
  // be drawn once and reused (shadow_map.h). False is always safe.
  bool fixed = false;
  // Level of detail: a lighter mesh drawn instead of `mesh` (in every channel
  // and the shadow of the camera alike) when `mesh`'s bounding sphere spans
  // fewer than `far_below_px` rows of the camera's image.
  MeshId far_mesh = kNoFarMesh;
  float far_below_px = 0.0f;
};

// A pinhole camera. The camera frame follows OpenGL: x right, y up, looking
// along -z. world_from_camera is that frame's pose in the (z-up) world.
struct CameraView {
  Eigen::Matrix4f world_from_camera = Eigen::Matrix4f::Identity();
  // The camera's pose one frame earlier (for optical flow; same intrinsics).
  Eigen::Matrix4f previous_world_from_camera = Eigen::Matrix4f::Identity();
  float fov_y_deg = 60.0f;
  float near_m = 0.1f;
  float far_m = 1000.0f;
  uint32_t width = 320;
  uint32_t height = 180;
  // Seeds this frame's sensor noise (look.h), so a frame is repeatable: the
  // daemon uses the frame id and the camera.
  uint32_t noise_seed = 0;
  // What the camera does to the light (protocol/effects.h; all off by
  // default). A lens distorts every channel alike; the rest change RGB only.
  effects::CameraEffects effects;
};

// Where one render writes its channels, one pointer per entry of
// channels::kPixelChannels: width*height pixels each in the channel's wire
// layout, tightly packed, top row first. A null pointer: that channel is
// neither drawn nor read back.
using FrameBuffers = std::array<uint8_t*, channels::kPixelChannelCount>;

}  // namespace sim4cv::render
