// The 3D ground truth of every labelled object: class, pose, velocity and an
// oriented 3D box. Static objects never move, so their boxes are worked out
// once, from the very meshes the renderer draws; the car's and the UAV's
// come from State each frame. Per frame, each box is projected into the
// camera beside the visible (mask) boxes.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <span>
#include <vector>

#include "server/render/ground_truth.h"
#include "server/render/projection.h"
#include "server/render/render_types.h"
#include "server/sim/state.h"

namespace sim4cv::render {

struct ObjectGroundTruth {
  InstanceId instance = kUnlabelled;
  uint32_t object_class = 0;                                          // proto ObjectClass value
  Eigen::Vector3d position = Eigen::Vector3d::Zero();                 // the 3D box's centre, world, m
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();   // box axes -> world
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();          // world, m/s; zero for static objects
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();         // world, rad/s; zero for static objects
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();             // along the box's own axes, m
  ImageRect projected_box;      // BoxProjector::Project of the 3D box: the extent if nothing occluded it
  bool has_visible_box = false;  // the frame's boxes hold one for this object (some pixel visible)
};

class ObjectCatalog {
 public:
  // Where an object's pose comes from.
  enum class Source : uint8_t { kStatic, kCar, kUav };

  // A static object: its box is the tight box around `model`'s vertices (in
  // the model's own frame, so trees include their crowns), placed by
  // `world_from_model` (a rigid transform).
  void AddStatic(InstanceId instance, uint32_t object_class, const Mesh& model,
                 const Eigen::Matrix4f& world_from_model);

  // A body State moves: its box is centred on the body's position and turns
  // with it.
  void AddBody(InstanceId instance, uint32_t object_class, Source source, const Eigen::Vector3d& half_extents);

  // Clears `out` (keeping its capacity: no allocation once warm) and appends,
  // ordered by instance id, every object that has a box in `visible` (as
  // BoxExtractor gives them: ordered by instance id) or whose projected 3D
  // box overlaps the image, i.e. also those in view but fully occluded.
  void Fill(const sim::State& state, const BoxProjector& camera, std::span<const GroundTruthBox> visible,
            std::vector<ObjectGroundTruth>& out) const;

  std::size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    InstanceId instance = kUnlabelled;
    uint32_t object_class = 0;
    Source source = Source::kStatic;
    Pose pose;  // of the box's centre; only for static objects
    Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();
  };
  void Insert(const Entry& entry);

  std::vector<Entry> entries_;  // ordered by instance id
};

}  // namespace sim4cv::render
