// The 3D ground truth of every labelled object: class, pose, velocity and an
// oriented 3D box. Static objects never move, so their boxes are worked out
// once, from the very meshes the renderer draws; moving ones (vehicles,
// traffic) are handed in each frame. Per frame, each box is projected into
// the camera beside the visible (mask) boxes.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <span>
#include <vector>

#include "server/render/ground_truth.h"
#include "server/render/projection.h"
#include "server/render/render_types.h"

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

// An object that moves: its box's centre follows `position` and turns with
// `orientation`. SceneGraphics lists these per frame.
struct MovingObject {
  InstanceId instance = kUnlabelled;
  uint32_t object_class = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();
};

class ObjectCatalog {
 public:
  // A static object: its box is the tight box around `model`'s vertices (in
  // the model's own frame, so trees include their crowns), placed by
  // `world_from_model` (a rigid transform).
  void AddStatic(InstanceId instance, uint32_t object_class, const Mesh& model,
                 const Eigen::Matrix4f& world_from_model);

  // Clears `out` (keeping its capacity: no allocation once warm) and appends,
  // ordered by instance id, every static object and every one of `moving`
  // (ordered by instance id, ids distinct from the static ones) that has a
  // box in `visible` (as BoxExtractor gives them: ordered by instance id) or
  // whose projected 3D box overlaps the image, i.e. also those in view but
  // fully occluded.
  void Fill(std::span<const MovingObject> moving, const BoxProjector& camera, std::span<const GroundTruthBox> visible,
            std::vector<ObjectGroundTruth>& out) const;

  std::size_t size() const { return entries_.size(); }

 private:
  void Insert(const MovingObject& entry);

  std::vector<MovingObject> entries_;  // static objects (at rest), ordered by instance id
};

}  // namespace sim4cv::render
