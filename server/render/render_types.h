// Plain data the renderer consumes and produces. No GL types leak out of here.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace sim4cv::render {

struct Vertex {
  float position[3];
  float normal[3];
  float color[3];  // linear RGB in [0, 1]
};

// Indexed triangle list; front faces wind counter-clockwise seen from outside.
struct Mesh {
  std::vector<Vertex> vertices;
  std::vector<uint32_t> indices;
};

// Index into the mesh list the Renderer was built with.
using MeshId = uint32_t;

// Instance id 0 marks unlabelled geometry (ground, road); labelled objects use
// 1..65535 and show up in the mask and the boxes.
using InstanceId = uint16_t;
inline constexpr InstanceId kUnlabelled = 0;

struct DrawItem {
  MeshId mesh = 0;
  Eigen::Matrix4f world_from_model = Eigen::Matrix4f::Identity();
  InstanceId instance = kUnlabelled;
};

// A pinhole camera. The camera frame follows OpenGL: x right, y up, looking
// along -z. world_from_camera is that frame's pose in the (z-up) world.
struct CameraView {
  Eigen::Matrix4f world_from_camera = Eigen::Matrix4f::Identity();
  float fov_y_deg = 60.0f;
  float near_m = 0.1f;
  float far_m = 1000.0f;
  uint32_t width = 320;
  uint32_t height = 180;
};

// Where one render writes its channels: width*height pixels each, tightly
// packed, top row first. A null pointer skips that channel's read-back.
struct FrameBuffers {
  uint8_t* rgb = nullptr;    // 3 bytes per pixel
  float* depth = nullptr;    // metres along the optical axis; +inf where nothing was hit
  uint16_t* mask = nullptr;  // InstanceId per pixel
};

}  // namespace sim4cv::render
