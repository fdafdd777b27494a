// Turns the simulation's Scene and State into what the Renderer draws: the
// meshes (built once), the static draw items, the labelled objects' 3D
// ground truth, and per frame the entities' items and each camera's view.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "server/render/ground_truth.h"
#include "server/render/object_catalog.h"
#include "server/render/render_types.h"
#include "server/render/traffic_graphics.h"
#include "server/render/walker_looks.h"
#include "server/sim/scene.h"
#include "server/sim/state.h"

namespace sim4cv::render {

class SceneGraphics {
 public:
  explicit SceneGraphics(const sim::Scene& scene);

  const std::vector<Mesh>& meshes() const { return meshes_; }

  // Brings everything that moves up to `state`: the draw items (with their
  // transforms of the previous Update, for optical flow), the labelled
  // objects and the moving objects' ground truth. Reuses its vectors: no
  // allocation per frame once the number of entities stops growing.
  void Update(const sim::State& state);

  // Static items followed by the entities, as of the last Update.
  const std::vector<DrawItem>& draw_items() const { return items_; }
  // Where the scene's street lanterns shine from (world), for Renderer::SetLamps.
  const std::vector<Eigen::Vector3f>& lamps() const { return lamps_; }
  // The headlights of every car that drives (entities and moving traffic;
  // parked cars are off), as of the last Update, for Renderer::SetHeadlights.
  std::span<const Headlight> headlights() const { return headlights_; }
  // Labelled objects (instance id, class) in instance-id order, as of the
  // last Update; the renderer fills in their unoccluded pixel counts.
  std::vector<LabelledObject>& labelled_objects() { return labelled_; }
  // The entities' 3D boxes, poses and velocities, as of the last Update.
  std::span<const MovingObject> moving_objects() const { return moving_; }

  // Class, pose and 3D box of every static labelled object (built once).
  const ObjectCatalog& catalog() const { return catalog_; }

  // The view of `camera` at `state`. A camera mounted on no entity (or on
  // one that is gone) stands fixed in the world: its offset is its position.
  CameraView CameraAt(const sim::CameraSpec& camera, const sim::State& state) const;

  // One more than the largest instance id a frame can hold.
  std::size_t instance_id_bound() const { return instance_id_bound_; }

 private:
  const sim::Scene& scene_;
  std::vector<Mesh> meshes_;
  // Fills each moving item's previous_world_from_model from previous_items_.
  void LinkPreviousTransforms();

  std::vector<DrawItem> items_;
  std::vector<DrawItem> previous_items_;  // items_ of the last Update
  std::size_t static_item_count_ = 0;
  MeshId car_mesh_ = 0, target_car_mesh_ = 0, uav_mesh_ = 0, rotor_mesh_ = 0;
  std::vector<std::pair<sim::EntityKind, MeshId>> registered_meshes_;  // a box per registered entity kind
  std::unique_ptr<WalkerLooks> walker_looks_;
  float uav_span_ = 0.0f;
  std::vector<Eigen::Vector3f> lamps_;
  std::vector<Headlight> headlights_;
  std::vector<LabelledObject> static_labelled_;
  std::vector<LabelledObject> labelled_;
  std::vector<MovingObject> moving_;
  std::unique_ptr<TrafficGraphics> traffic_;  // map scenes with traffic only
  ObjectCatalog catalog_;
  std::size_t instance_id_bound_ = 0;
};

}  // namespace sim4cv::render
